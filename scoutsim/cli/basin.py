"""``scoutsim basin``: the basin map. Run a grid of initial states (forward speed x pitch
rate x height) for each model and floor in parallel, report the fraction of valid starts
that reach steady bounding and the cycle's speed, and write basin.csv, basin.json and the
map basin.png (listed in manifest.json once written whole). Ctrl-C keeps the finished
starts: basin.csv with those rows, marked partial, exit 130.

    scoutsim basin [--controller {table-i,pitch-feedback}] [--model LIST] [--floors LIST]
                   [--speeds LIST] [--pitch-rates LIST] [--heights LIST] [--duration S]
                   [--robot FILE] [--out DIR] [--workers N] [--no-progress] [--no-plots]

Exit code 1 if a start crashed (the table and files are still written).
"""

from __future__ import annotations

import csv
import inspect
import math
import os
import sys
import time

from ..analysis.basin import (
    BASIN_COLUMNS,
    DEFAULT_FLOORS,
    DEFAULT_HEIGHTS,
    DEFAULT_PITCH_RATES,
    DEFAULT_SPEEDS,
    basin_of_attraction,
    basin_stats,
    basin_tasks,
    pitch_rate_deg_s,
    run_basin_tasks,
)
from ..analysis.parallel import NotSendableError
from ..io.run_directory import RunDirectory
from ..parameters import floor_label
from ._common import (
    SCOUT_FLOOR_FRICTION,
    add_controller_option,
    add_duration_option,
    add_models_option,
    add_plots_option,
    check_expected_time,
    controller_choice,
    controller_label,
    float_list,
    friction_list,
    integrator,
    load_parameters,
    make_controller,
    out_dir,
    positive_int,
    show_progress,
    usage_errors,
    write_json,
)
from ._given import refuse_given

NAME = "basin"

#: simulated time per start [s]: basin_of_attraction()'s default
DEFAULT_DURATION_S = inspect.signature(basin_of_attraction).parameters["duration"].default


def _defaults(values) -> str:
    return ",".join(f"{v:g}" for v in values)


def register(sub, common) -> None:
    basin = sub.add_parser(
        NAME,
        parents=[common],
        help="basin map: which starts reach steady bounding, per model and floor",
        description="Run a grid of initial states (forward speed x pitch rate x height; "
        "level torso, legs at their touchdown angles) for each model and floor in "
        "parallel and report the fraction that reaches steady bounding "
        "(GaitMetrics.is_steady_bounding: completed, >= 7 steady strides after "
        "the 2 s transient, stride-period CV <= 5 %) and the cycle's speed. "
        "Starts with a toe below the ground are recorded as invalid_start and "
        "left out of the fraction. Writes basin.csv, basin.json and the map "
        "basin.png to DIR.",
    )
    add_duration_option(basin, DEFAULT_DURATION_S, "simulated time per start")
    add_models_option(basin)
    add_controller_option(basin)
    basin.add_argument(
        "--floors",
        type=friction_list,
        default=None,
        metavar="LIST",
        help="comma-separated toe friction coefficients, 'inf' = no slip "
        f"(default: {SCOUT_FLOOR_FRICTION:g},inf; --friction MU runs one)",
    )
    basin.add_argument(
        "--speeds",
        type=float_list(),
        default=list(DEFAULT_SPEEDS),
        metavar="LIST",
        help="initial forward speeds [m/s] (default: " + _defaults(DEFAULT_SPEEDS) + ")",
    )
    rates_deg_s = [pitch_rate_deg_s(w) for w in DEFAULT_PITCH_RATES]  # the edge: deg/s
    basin.add_argument(
        "--pitch-rates",
        type=float_list(),
        default=rates_deg_s,
        metavar="LIST",
        help="initial pitch rates [deg/s], positive = nose "
        "rising (default: " + _defaults(rates_deg_s) + ")",
    )
    basin.add_argument(
        "--heights",
        type=float_list(positive=True),
        default=list(DEFAULT_HEIGHTS),
        metavar="LIST",
        help="initial torso COM heights [m] (default: " + _defaults(DEFAULT_HEIGHTS) + ")",
    )
    add_plots_option(basin, True, "the map basin.png")
    basin.add_argument(
        "--workers",
        type=positive_int,
        default=None,
        metavar="N",
        help="parallel processes (default: os.cpu_count(); 1 runs in this process)",
    )
    basin.set_defaults(func=execute)


def format_basin(per: dict, n_grid: int, duration: float, controller: str = "table-i") -> str:
    """The human-readable basin table (one row per model and floor)."""
    head = (
        "model",
        "floor",
        "starts",
        "invalid",
        "errors",
        "valid",
        "steady",
        "fraction",
        "fell",
        "other",
        "cycle m/s",
    )
    lines = [
        f"scoutsim basin ({controller_label(controller)} controller): {n_grid} starts "
        f"per model and floor, {duration:g} s each; "
        "fraction = steady bounding / valid starts (errors: starts the study could "
        "not run, left out); cycle m/s = median speed of the starts that bound",
        "  " + "  ".join(f"{h:>9}" for h in head),
    ]
    for key, s in per.items():
        frac = s["fraction_steady_bounding"]
        fell = s["outcomes"].get("fell", 0)
        other = s["n_valid"] - s["outcomes"].get("completed", 0) - fell
        v = s.get("median_cycle_speed_m_s")
        mu = s.get("friction")
        vals = (
            s.get("model", key),
            "-" if mu is None else floor_label(mu),
            s["n_starts"],
            s["n_invalid_start"],
            s.get("n_errors", 0),
            s["n_valid"],
            s["n_steady_bounding"],
            "n/a" if frac is None else f"{frac:.3f}",
            fell,
            other,
            "-" if v is None else f"{v:.3f}",
        )
        lines.append("  " + "  ".join(f"{x!s:>9}" for x in vals))
    return "\n".join(lines)


def _write_rows(path, rows) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=BASIN_COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if r.get(k) is None else r[k]) for k in BASIN_COLUMNS})


def execute(args) -> int:
    if args.floors is not None:
        refuse_given(args, ("friction",), "with --floors (give the floor in the list)")
    robot, cparams = load_parameters(args.robot)
    law, cparams = controller_choice(args.controller, cparams)
    controller = make_controller(law, cparams, robot, on_workers=True)
    integ = integrator(args)
    out = out_dir(args.out)
    models = args.model
    workers = args.workers or os.cpu_count() or 1
    progress = show_progress(args)
    grid = [(v, w, h) for v in args.speeds for w in args.pitch_rates for h in args.heights]
    floors = (
        args.floors
        if args.floors is not None
        else [args.friction]
        if "friction" in getattr(args, "given", ())
        else list(DEFAULT_FLOORS)
    )
    check_expected_time(
        args,
        {m: len(grid) * len(floors) * args.duration for m in models},
        workers=workers,
        what=f"the basin map of {len(grid)} starts",
    )
    tasks = basin_tasks(
        models,
        floors,
        args.speeds,
        [math.radians(w) for w in args.pitch_rates],  # deg/s -> rad/s, once
        args.heights,
        args.duration,
        robot,
        controller,
        integ,
    )
    if args.duration < 5.0:
        print(
            f"scoutsim basin: note: --duration {args.duration:g} s is short; steady bounding "
            "needs >= 7 strides after the 2 s transient, so (almost) no start can qualify",
            file=sys.stderr,
        )

    wall0 = time.perf_counter()
    finished: dict = {}
    rd = RunDirectory(
        out,
        command=" ".join(["scoutsim"] + sys.argv[1:]),
        info={"kind": "basin", "n_starts": len(tasks), "controller": args.controller},
    )
    try:
        with usage_errors(NotSendableError):  # said before the first start runs
            rows = run_basin_tasks(
                tasks, workers, progress, on_result=lambda i, row: finished.__setitem__(i, row)
            )
    except KeyboardInterrupt:
        # what was computed is kept: the finished starts, marked partial (no statistics
        # or map of a grid with holes)
        rows = [finished[i] for i in sorted(finished)]
        rd.open()
        rd.write("basin.csv", lambda p: _write_rows(p, rows))
        rd.finish(outcome="interrupted", partial=True)
        print(
            f"scoutsim basin: interrupted; {len(rows)} of {len(tasks)} starts are done, "
            f"written to {out}/basin.csv (marked partial in manifest.json)",
            file=sys.stderr,
        )
        return 130
    wall = time.perf_counter() - wall0

    rd.open()
    rd.write("basin.csv", lambda p: _write_rows(p, rows))
    per = basin_stats(rows, models, floors if len(floors) > 1 else None)
    summary = {
        "controller": args.controller,
        "fraction_steady_bounding": {m: s["fraction_steady_bounding"] for m, s in per.items()},
        "models": per,
        "grid": {
            "speeds_m_s": args.speeds,
            "pitch_rates_deg_s": args.pitch_rates,
            "heights_m": args.heights,
            "duration_s": args.duration,
            "floors": ["inf" if math.isinf(mu) else mu for mu in floors],
            "n_starts_per_model": len(grid),
        },
        "criterion": "GaitMetrics.is_steady_bounding(): outcome completed, >= 7 steady "
        "strides after the 2 s transient, stride-period CV <= 0.05; "
        "invalid_start excluded from the denominator",
        "wall_time_s": wall,
        "workers": workers,
    }
    rd.write("basin.json", lambda p: write_json(p, summary))
    written = "basin.csv, basin.json"
    if args.plots:
        from ..presentation.plots import plot_basin_map
        from ..state import InitialState

        d = InitialState()
        rd.write(
            "basin.png",
            lambda p: plot_basin_map(
                rows,
                p,
                default_start=(d.dx, math.degrees(d.dtheta)),
                controller=controller_label(law)
                + ("" if law == args.controller else f" ({args.controller})"),
            ),
        )
        written += ", basin.png"
    rd.finish(outcome="completed", partial=False)

    print(format_basin(per, len(grid), args.duration, law))
    n_invalid = sum(s["n_invalid_start"] for s in per.values())
    if n_invalid:
        example = next(r for r in rows if r["outcome"] == "invalid_start")
        print(
            f"{n_invalid} invalid start(s) (toe below the ground), e.g. speed "
            f"{example['speed']:g} m/s, pitch rate {example['pitch_rate_deg_s']:g} deg/s, "
            f"height {example['height']:g} m: {example.get('error', '')}"
        )
    print(
        f"wall time {wall:.1f} s with {min(workers, len(tasks))} worker(s); "
        f"wrote {written} to {out}/"
    )
    errors = [r for r in rows if r.get("status") == "error"]
    for r in errors[:5]:
        print(
            f"scoutsim basin: start model {r['model']}, speed {r['speed']:g}, pitch rate "
            f"{r['pitch_rate_deg_s']:g}, height {r['height']:g} could not run (an error "
            f"of the study, not of the robot; left out of the fraction): {r['error']}",
            file=sys.stderr,
        )
    if len(errors) > 5:
        print(
            f"scoutsim basin: ... {len(errors) - 5} more such starts (basin.csv, status 'error')",
            file=sys.stderr,
        )
    return 1 if errors else 0
