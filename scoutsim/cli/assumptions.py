"""``scoutsim assumptions``: the paper's question asked of one controller. Run it on a
ladder of models (ideal actuator, torque-speed line only, Model I, Model II, Model II with
the virtual Scout II's error sources) and with each effect of the richest model switched
off one at a time; print the percent difference of each gait metric from the reference
as a Markdown table and write assumptions.csv, assumptions.json and the figure
assumptions.png (:mod:`scoutsim.analysis.assumptions`).

    scoutsim assumptions [--controller {table-i,pitch-feedback,FILE,MODULE:FACTORY}]
                         [--robot FILE] [--reference CASE] [--duration S] [--friction MU]
                         [--basin-grid NxM] [--workers N] [--scheduler ADDRESS]
                         [--out DIR] [--plots/--no-plots] [--quick]

Exit code 1 if a case could not be run (an error of the study; the table is still written).
"""

from __future__ import annotations

import os
import sys
import time

from ..analysis.assumption_cases import RICHEST, RUNG_NAMES, SWITCH_NAMES
from ..analysis.assumptions import assumption_study, basin_grid
from ..analysis.parallel import NotSendableError
from ..io.run_directory import RunDirectory
from ._common import (
    UsageError,
    add_controller_option,
    add_duration_option,
    add_parallel_options,
    add_plots_option,
    controller_choice,
    controller_label,
    load_parameters,
    make_controller,
    out_dir,
    show_progress,
    usage_errors,
    write_json,
)

NAME = "assumptions"
#: simulated time of every run [s]
DEFAULT_DURATION_S = 10.0
#: --quick: a shorter run and a basin of one start
QUICK_DURATION_S = 5.0
DEFAULT_BASIN_GRID = "2x1"


def _grid(text: str) -> tuple[int, int]:
    parts = text.lower().split("x")
    try:
        n = tuple(int(p) for p in parts)
    except ValueError:
        n = ()
    if len(n) != 2 or min(n) < 0:
        raise UsageError(
            f"--basin-grid {text!r} is not allowed: give SPEEDSxPITCH_RATES, two counts "
            ">= 0 (e.g. 2x1; 0x0: no basin)"
        )
    return n[0], n[1]


def register(sub, common) -> None:
    cases = ", ".join(RUNG_NAMES + tuple("-" + s for s in SWITCH_NAMES))
    p = sub.add_parser(
        NAME,
        parents=[common],
        help="which modelling assumptions change a controller's bound (the paper's question)",
        description="Run one controller on a ladder of models (ideal actuator with "
        "constant maximum torque; the torque-speed line only; Model I; Model II; Model II "
        "with the virtual Scout II's error sources) and with each effect of the richest "
        "model switched off one at a time; compare the gait metrics (from the default "
        "start, with the energy accounting) and the basin fraction (a small grid of "
        "starts) with the reference in percent, as the paper's Fig. 12. Writes "
        "assumptions.csv, assumptions.json and assumptions.png to DIR. Cases: " + cases,
    )
    add_duration_option(p, DEFAULT_DURATION_S, "simulated time of every run")
    add_controller_option(p)
    p.add_argument(
        "--reference",
        default=RICHEST,
        metavar="CASE",
        help=f"the case the percents are taken from (default: {RICHEST})",
    )
    p.add_argument(
        "--basin-grid",
        default=DEFAULT_BASIN_GRID,
        metavar="NxM",
        help="basin starts: N speeds over 0.8-1.6 m/s x M pitch rates over 50-200 deg/s "
        f"at 0.33 m (one: 1.2 m/s, 150 deg/s; 0x0: no basin; default: {DEFAULT_BASIN_GRID})",
    )
    add_parallel_options(p)
    p.add_argument(
        "--quick",
        action="store_true",
        help=f"{QUICK_DURATION_S:g} s runs and a basin of one start (where --duration / "
        "--basin-grid are at their defaults)",
    )
    add_plots_option(p, True, "assumptions.png")
    p.set_defaults(func=execute)


def execute(args) -> int:
    robot, cparams = load_parameters(args.robot)
    law, cparams = controller_choice(args.controller, cparams)
    controller = make_controller(law, cparams, robot, on_workers=True)
    duration, grid_text = args.duration, args.basin_grid
    if args.quick:  # the quick values replace the defaults, not values given
        if duration == DEFAULT_DURATION_S:
            duration = QUICK_DURATION_S
        if grid_text == DEFAULT_BASIN_GRID:
            grid_text = "1x1"
    grid = basin_grid(*_grid(grid_text))
    workers = 1 if args.scheduler else (args.workers or os.cpu_count() or 1)
    out = out_dir(args.out)
    wall0 = time.perf_counter()
    with usage_errors(ValueError, NotSendableError):
        result = assumption_study(
            controller,
            robot,
            reference=args.reference,
            duration=duration,
            friction_coefficient=args.friction,
            basin=grid,
            workers=workers,
            scheduler=args.scheduler,
            progress=show_progress(args),
        )
    wall = time.perf_counter() - wall0
    result.settings["controller"] = controller_label(law)
    rd = RunDirectory(
        out,
        command=" ".join(["scoutsim"] + sys.argv[1:]),
        info={"kind": "assumptions", "controller": args.controller},
    )
    rd.open()
    rd.write("assumptions.csv", result.to_csv)
    rd.write("assumptions.json", lambda path: write_json(path, result.to_dict()))
    written = "assumptions.csv, assumptions.json"
    if args.plots:
        from ..presentation.assumption_figure import plot_assumptions

        rd.write("assumptions.png", lambda path: plot_assumptions(result, path))
        written += ", assumptions.png"
    rd.finish(outcome="completed", partial=False)
    n_basin = len(grid["speeds"]) * len(grid["pitch_rates"]) * len(grid["heights"])
    print(
        f"scoutsim assumptions ({controller_label(law)} controller): {duration:g} s per run "
        f"from the default start, basin of {n_basin} start(s), floor mu = {args.friction:g}; "
        f"percent difference from {args.reference}"
    )
    print(result.markdown())
    print(f"wall time {wall:.1f} s; wrote {written} to {out}/")
    errors = [r for r in result.rows if r.get("status") == "error"]
    for r in errors:
        print(
            f"scoutsim assumptions: case {r['case']} could not run (an error of the study): "
            f"{r.get('error', '')}",
            file=sys.stderr,
        )
    return 1 if errors else 0
