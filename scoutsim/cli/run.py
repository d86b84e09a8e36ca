"""``scoutsim run``: simulate one bounding run, print a summary table (or JSON) and write
the run's tables and summary (and, on request, figures and the older file formats) to the
output directory.

    scoutsim run [--model {ideal,I,II,passive}] [--duration S] [--robot FILE] [--out DIR]
                 [--rtol X] [--atol X] [--friction MU] [--speed V] [--height Y]
                 [--pitch-rate W] [--steps] [--format {parquet,csv}] [--plots] [--csv]
                 [--npz] [--no-progress] [--quiet] [--json]

Written to DIR: ``timeseries.parquet`` (every control sample, every signal, with the
outcome, statistics and provenance), ``events.parquet`` (every event with the exact state
before and after its transition), ``summary.json``; ``steps.parquet`` with ``--steps``
(every integrator step); ``.csv.gz`` instead of ``.parquet`` without pyarrow or with
``--format csv``. ``--plots``: run.png and torque_speed.png; ``--csv``: the plain
timeseries.csv; ``--npz``: result.npz. :meth:`scoutsim.SimulationResult.load` reads DIR
(or result.npz) back bit for bit.

Exit code 1 if the integration failed numerically, 130 if interrupted (the data so far is
still written); a fall is a completed run (exit 0, the summary says so).
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

from ..result import COLUMN_UNITS, column_unit
from ..run_directory import MANIFEST, RunDirectory
from ..state import InitialState
from ._common import (MODELS, command_wall_time, dumps, finite_float, integrator,
                      load_parameters, out_dir, positive_float, show_progress, usage_errors,
                      write_json)

NAME = "run"

#: Unit of each ``result.columns()`` name (one home: :data:`scoutsim.result.COLUMN_UNITS`),
#: written into the header of ``timeseries.csv`` as ``name [unit]``.
TIMESERIES_UNITS = COLUMN_UNITS


_DEFAULT_START = InitialState()


def register(sub, common) -> None:
    from ..tables import FORMATS
    run = sub.add_parser(
        NAME, parents=[common], help="simulate one run, print a summary, write its tables",
        description="Simulate one bounding run and write to DIR: timeseries and events tables "
                    "(Parquet, or gzip-compressed CSV without pyarrow) and summary.json; "
                    "figures with --plots. SimulationResult.load(DIR) reads the run back.")
    run.add_argument("--model", choices=MODELS, default="II",
                     help="actuator/transmission model (default: II)")
    run.add_argument("--speed", type=finite_float, default=None, metavar="V",
                     help=f"initial forward speed [m/s] (default: {_DEFAULT_START.dx:g})")
    run.add_argument("--height", type=positive_float, default=None, metavar="Y",
                     help=f"initial torso COM height [m] (default: {_DEFAULT_START.y:g})")
    run.add_argument("--pitch-rate", type=finite_float, default=None, metavar="W",
                     help="initial pitch rate [deg/s] (default: "
                     f"{math.degrees(_DEFAULT_START.dtheta):g})")
    run.add_argument("--steps", action="store_true",
                     help="also record every integrator step (steps table: time, state, "
                          "plant modes)")
    run.add_argument("--format", choices=FORMATS, default=None,
                     help="format of the tables: parquet (default when pyarrow is "
                          "installed) or csv (gzip-compressed, the default otherwise)")
    run.add_argument("--plots", action="store_true",
                     help="also draw run.png (pitch, height, leg angles and states, hip "
                          "torques; runs over 4 s: an overview and the last strides) and "
                          "torque_speed.png (paper Fig. 11)")
    run.add_argument("--no-plots", action="store_true",
                     help="no figures (the default; kept for older scripts)")
    run.add_argument("--csv", action="store_true",
                     help="also write timeseries.csv (plain CSV, one row per sample)")
    run.add_argument("--npz", action="store_true",
                     help="also write result.npz (the whole result in one NumPy file)")
    run.add_argument("--json", action="store_true",
                     help="print the summary as JSON on stdout instead of the table")
    run.set_defaults(func=execute)


def write_timeseries_csv(result, path) -> Path:
    """Write ``result.columns()`` as CSV, one row per sample, header ``name [unit]``; floats
    with 17 significant digits, so ``np.loadtxt`` reads every value back bit for bit."""
    import numpy as np
    cols = result.columns()
    names = list(cols)
    header = ",".join(f"{n} [{u}]" if (u := column_unit(n)) else n for n in names)
    data = np.column_stack([np.asarray(cols[n], dtype=float) for n in names]) if names else \
        np.zeros((0, 0))
    path = Path(path)
    # 17 significant digits: every float64 reads back to the same bits
    np.savetxt(path, data, delimiter=",", header=header, comments="", fmt="%.17g")
    return path


def _fmt(v, spec: str, unit: str = "") -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:{spec}}{(' ' + unit) if unit else ''}"


def _pair(a, b, spec: str, unit: str) -> str:
    if a is None and b is None:
        return "n/a"
    return f"{_fmt(a, spec)} / {_fmt(b, spec)}{(' ' + unit) if unit else ''}"


def format_summary(summary: dict, *, duration: float, wall_s: float, t_end: float,
                   friction: float | None = None, load_s: float | None = None,
                   command_wall_s: float | None = None) -> str:
    """The human-readable summary table of a run: ``wall_s`` is the simulation's wall time
    [s] (its real-time factor is t_end / wall_s), ``load_s`` the time the compiled core took
    to get ready before it, ``command_wall_s`` the whole command's."""
    outcome = summary.get("outcome")
    if outcome != "completed" and t_end is not None:
        outcome = f"{outcome} at t = {t_end:.3f} s"
    rtf = (t_end / wall_s) if wall_s > 0 and t_end else None
    rows = [
        ("outcome", outcome),
        ("mean forward speed", _fmt(summary.get("mean_speed_m_s"), ".3f", "m/s")),
        ("stride frequency", _fmt(summary.get("stride_frequency_hz"), ".3f", "Hz")),
        ("duty factor back / front", _pair(summary.get("duty_factor_back"),
                                           summary.get("duty_factor_front"), ".3f", "")),
        ("pitch max / min", _pair(summary.get("pitch_max_deg"), summary.get("pitch_min_deg"),
                                  ".2f", "deg")),
        ("COM height max / min", _pair(summary.get("height_max_m"), summary.get("height_min_m"),
                                       ".4f", "m")),
        ("largest friction ratio |F_t|/F_n", _fmt(summary.get("max_friction_ratio"), ".3f")),
        ("steady strides", _fmt(summary.get("n_steady_strides"), "d")
         + (f" (of {summary['n_strides']})" if summary.get("n_strides") is not None else "")),
        ("steady bounding", {True: "yes", False: "no"}.get(summary.get("steady_bounding"), "n/a")),
        ("simulation", (f"{wall_s:.3f} s wall, real-time factor {rtf:.0f}x" if rtf else
                        _fmt(wall_s, ".3f", "s"))),
    ]
    if load_s is not None:
        rows.append(("compiled core", f"ready in {load_s:.2f} s (loaded from the cache, or "
                                      "compiled on a first run)"))
    if command_wall_s is not None:
        rows.append(("command wall time", f"{command_wall_s:.2f} s (start-up, simulation, "
                                          "outputs)"))
    width = max(len(k) for k, _ in rows)
    model = summary.get("model")
    floor = ("" if friction is None else
             ", floor: no slip" if math.isinf(friction) else f", floor: Coulomb mu = {friction:g}")
    lines = [f"scoutsim run: model {model}, {duration:g} s requested{floor}"]
    lines += [f"  {k:<{width}}  {v}" for k, v in rows]
    if summary.get("n_steady_strides") == 0 and summary.get("outcome") == "completed":
        lines.append("  (no steady strides: the gait means need strides after the 2 s "
                     "transient; run longer)")
    return "\n".join(lines)


def execute(args) -> int:
    from ..simulation import InitialState, simulate, warm_up
    robot, controller = load_parameters(args.robot)
    integ = integrator(args)
    changes = {}
    if args.speed is not None:
        changes["dx"] = args.speed
    if args.height is not None:
        changes["y"] = args.height
    if args.pitch_rate is not None:
        changes["dtheta"] = math.radians(args.pitch_rate)
    init = InitialState(**changes)
    out = out_dir(args.out)
    progress = show_progress(args)

    load_s = warm_up()
    wall0 = time.perf_counter()
    with usage_errors():  # invalid initial state or option
        result = simulate(robot, controller, init, args.duration, model=args.model,
                          integrator=integ, friction_coefficient=args.friction,
                          progress=progress, record_steps=args.steps)
    wall = time.perf_counter() - wall0

    summary = result.summary()
    interrupted = result.outcome == "interrupted"
    info = {"scoutsim_version": result.provenance.get("scoutsim_version"),
            "model": args.model, "duration_s": args.duration, "t_end": result.t_end}
    with RunDirectory(out, command=" ".join(["scoutsim"] + sys.argv[1:]), info=info) as rd:
        for path in result.save_tables(out, fmt=args.format):
            rd.add(path.name)
        rd.write("summary.json", lambda p: write_json(p, summary))
        if args.csv:
            rd.write("timeseries.csv", lambda p: write_timeseries_csv(result, p))
        if args.npz:
            rd.write("result.npz", lambda p: result.save(p))
        if args.plots and not args.no_plots:
            from ..presentation.plots import plot_run, plot_torque_speed
            rd.write("run.png", lambda p: plot_run(result, p, overview="auto"))
            rd.write("torque_speed.png", lambda p: plot_torque_speed(result, "both", p))
        rd.finish(outcome=result.outcome, partial=interrupted)
    files = [out / name for name in rd.files] + [out / MANIFEST]

    if args.json:
        print(dumps(summary))
    else:
        print(format_summary(summary, duration=args.duration, wall_s=wall, t_end=result.t_end,
                             friction=args.friction, load_s=load_s,
                             command_wall_s=command_wall_time()))
        print(f"wrote {', '.join(f.name for f in files)} to {out}/")
    if result.outcome == "numerical_failure":
        print("scoutsim run: the integration failed numerically (see summary.json and the "
              "timeseries table); try a smaller --rtol", file=sys.stderr)
        return 1
    if result.outcome == "interrupted":
        return 130
    return 0
