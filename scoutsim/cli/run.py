"""``scoutsim run``: simulate one bounding run, print a summary table (or JSON) and write
the time series, the saved result, the summary and plots to the output directory.

    scoutsim run [--model {ideal,I,II,passive}] [--duration S] [--robot FILE] [--out DIR]
                 [--rtol X] [--atol X] [--friction MU] [--speed V] [--height Y]
                 [--pitch-rate W] [--no-plots] [--no-progress] [--json]

Exit code 1 if the integration failed numerically, 130 if interrupted (the data so far is
still written); a fall is a completed run (exit 0, the summary says so).
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

from ..result import COLUMN_UNITS, column_unit
from ..state import InitialState
from ._common import (MODELS, dumps, finite_float, integrator, load_parameters, out_dir,
                      positive_float, show_progress, usage_errors, write_json)

NAME = "run"

#: Unit of each ``result.columns()`` name (one home: :data:`scoutsim.result.COLUMN_UNITS`),
#: written into the header of ``timeseries.csv`` as ``name [unit]``.
TIMESERIES_UNITS = COLUMN_UNITS


_DEFAULT_START = InitialState()


def register(sub, common) -> None:
    run = sub.add_parser(
        NAME, parents=[common], help="simulate one run, print a summary, write data and plots",
        description="Simulate one bounding run and write to DIR: timeseries.csv, result.npz, "
                    "summary.json, run.png and torque_speed.png.")
    run.add_argument("--model", choices=MODELS, default="II",
                     help="actuator/transmission model (default: II)")
    run.add_argument("--speed", type=finite_float, default=None, metavar="V",
                     help=f"initial forward speed [m/s] (default: {_DEFAULT_START.dx:g})")
    run.add_argument("--height", type=positive_float, default=None, metavar="Y",
                     help=f"initial torso COM height [m] (default: {_DEFAULT_START.y:g})")
    run.add_argument("--pitch-rate", type=finite_float, default=None, metavar="W",
                     help="initial pitch rate [deg/s] (default: "
                     f"{math.degrees(_DEFAULT_START.dtheta):g})")
    run.add_argument("--no-plots", action="store_true", help="do not write run.png and "
                     "torque_speed.png")
    run.add_argument("--json", action="store_true",
                     help="print the summary as JSON on stdout instead of the table")
    run.set_defaults(func=execute)


def write_timeseries_csv(result, path) -> Path:
    """Write ``result.columns()`` as CSV, one row per sample, header ``name [unit]``."""
    import numpy as np
    cols = result.columns()
    names = list(cols)
    header = ",".join(f"{n} [{u}]" if (u := column_unit(n)) else n for n in names)
    data = np.column_stack([np.asarray(cols[n], dtype=float) for n in names]) if names else \
        np.zeros((0, 0))
    path = Path(path)
    np.savetxt(path, data, delimiter=",", header=header, comments="", fmt="%.12g")
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
                   friction: float | None = None) -> str:
    """The human-readable summary table of a run."""
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
        ("wall time", _fmt(wall_s, ".2f", "s")),
        ("real-time factor", (f"{rtf:.2f}x (simulated / wall time)" if rtf else "n/a")),
    ]
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
    from ..simulation import InitialState, simulate
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

    wall0 = time.perf_counter()
    with usage_errors():  # invalid initial state or option
        result = simulate(robot, controller, init, args.duration, model=args.model,
                          integrator=integ, friction_coefficient=args.friction,
                          progress=progress)
    wall = time.perf_counter() - wall0

    summary = result.summary()
    files = [out / "timeseries.csv", out / "result.npz", out / "summary.json"]
    write_timeseries_csv(result, files[0])
    result.save(files[1])
    write_json(files[2], summary)
    if not args.no_plots:
        from ..presentation.plots import plot_run, plot_torque_speed
        plot_run(result, out / "run.png")
        plot_torque_speed(result, "both", out / "torque_speed.png")
        files += [out / "run.png", out / "torque_speed.png"]

    if args.json:
        print(dumps(summary))
    else:
        print(format_summary(summary, duration=args.duration, wall_s=wall, t_end=result.t_end,
                             friction=args.friction))
        print(f"wrote {', '.join(f.name for f in files)} to {out}/")
    if result.outcome == "numerical_failure":
        print("scoutsim run: the integration failed numerically (see summary.json and "
              "result.npz); try a smaller --rtol", file=sys.stderr)
        return 1
    if result.outcome == "interrupted":
        return 130
    return 0
