"""Command-line interface: ``scoutsim run``, ``scoutsim basin`` and ``scoutsim compare``.

    scoutsim run [--model {ideal,I,II,passive}] [--duration S] [--robot FILE] [--out DIR]
                 [--rtol X] [--atol X] [--friction MU] [--speed V] [--height Y]
                 [--pitch-rate W] [--no-plots] [--no-progress] [--json]
    scoutsim basin [--model LIST] [--speeds LIST] [--pitch-rates LIST] [--heights LIST]
                   [--duration S] [--robot FILE] [--out DIR] [--workers N] [--no-progress]
    scoutsim compare (LOG... | --example) [--models LIST] [--duration S] [--robot FILE]
                     [--out DIR] [--friction MU] [--transient S] [--no-progress] [--no-plots]
    scoutsim plot RESULT.npz|LOG [--out FILE] [--t0 S] [--t1 S]
    scoutsim animate RESULT.npz --out FILE.gif|.mp4 [--fps N] [--t0 S] [--t1 S] [--dpi N]

Presentation layer: all computation is SI (angles in rad); degrees appear only in what is
printed and plotted, converted here with :func:`math.degrees` / :func:`math.radians`.

Exit codes: 0 success (also when the robot fell: the summary says so), 1 numerical failure
(``run``) or a crashed start (``basin``), 2 bad usage, parameter file, initial state or
experiment log (``compare``),
130 interrupted (Ctrl-C; the data computed so far is still written).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys
import time
from pathlib import Path

from .analysis.basin import (BASIN_COLUMNS, DEFAULT_FLOORS, DEFAULT_HEIGHTS, DEFAULT_PITCH_RATES,
                             DEFAULT_SPEEDS, basin_stats, basin_tasks, floor_label,
                             run_basin_tasks)
from .parameters import DEFAULT_FRICTION_COEFFICIENT

__all__ = ["main", "build_parser", "TIMESERIES_UNITS", "column_unit", "write_timeseries_csv",
           "format_summary", "format_basin"]

MODELS = ("ideal", "I", "II", "passive")
_LIST_OPTIONS = ("--speeds", "--pitch-rates", "--heights", "--model", "--models", "--floors", "--pitch-rate")

#: Unit of each ``result.columns()`` name, by prefix (first match wins); written into the
#: header of ``timeseries.csv`` as ``name [unit]``. Mode columns are codes without a unit.
TIMESERIES_UNITS = (
    ("t", "s", True), ("x", "m", True), ("y", "m", True), ("theta", "rad", True),
    ("phi_", "rad", False), ("alpha_", "rad", False), ("dx", "m/s", True),
    ("dy", "m/s", True), ("dtheta", "rad/s", True), ("dphi_", "rad/s", False),
    ("dalpha_", "rad/s", False), ("leg_length_", "m", False), ("ground_force_", "N", False),
    ("leg_axial_force_", "N", False), ("hip_torque_", "N m", False),
    ("motor_current_", "A", False), ("motor_speed_", "rad/s", False),
    ("belt_deflection_", "rad", False), ("stiction_holding_torque_", "N m", False),
    ("toe_x_", "m", False), ("toe_y_", "m", False), ("toe_velocity_x_", "m/s", False),
    ("strut_force_", "N", False), ("belt_torque_", "N m", False),
    ("battery_voltage", "V", True), ("energy", "J", True),
)


class _UsageError(Exception):
    """A problem with the user's input: message on stderr, exit code 2."""


# -----------------------------------------------------------------------------------------
# argument types
# -----------------------------------------------------------------------------------------
#: Toe friction of the CLI's jobs: the package's one default floor
SCOUT_FLOOR_FRICTION = DEFAULT_FRICTION_COEFFICIENT


def _positive_float(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (math.isfinite(v) and v > 0):
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: must be a finite number > 0")
    return v


def _finite_float(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: must be finite")
    return v


def _friction(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (v >= 0):
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: must be >= 0 "
                                         "('inf' = no slip)")
    return v


def _friction_list(text: str) -> list:
    vals = [_friction(x.strip()) for x in text.split(",") if x.strip()]
    if not vals:
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: give at least one value")
    if len(set(vals)) != len(vals):
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: a floor is repeated")
    return vals


def _positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: must be >= 1")
    return v


def _float_list(positive: bool = False):
    def parse(text: str) -> list[float]:
        items = [s.strip() for s in text.split(",")]
        if not items or any(s == "" for s in items):
            raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list of numbers")
        return [(_positive_float if positive else _finite_float)(s) for s in items]
    return parse


def _model_list(text: str) -> list[str]:
    items = [s.strip() for s in text.split(",") if s.strip()]
    if not items:
        raise argparse.ArgumentTypeError("give at least one model")
    bad = [m for m in items if m not in MODELS]
    if bad:
        raise argparse.ArgumentTypeError(f"unknown model(s) {bad}; choose from {', '.join(MODELS)}")
    return list(dict.fromkeys(items))


def _join_list_values(argv: list[str]) -> list[str]:
    """Let ``--pitch-rates -100,-50`` work: argparse would take "-100,-50" for an option."""
    out, i = [], 0
    while i < len(argv):
        tok = argv[i]
        if (tok in _LIST_OPTIONS and i + 1 < len(argv) and len(argv[i + 1]) > 1
                and argv[i + 1][0] == "-" and (argv[i + 1][1].isdigit() or argv[i + 1][1] == ".")):
            out.append(f"{tok}={argv[i + 1]}")
            i += 2
            continue
        out.append(tok)
        i += 1
    return out


# -----------------------------------------------------------------------------------------
# parser
# -----------------------------------------------------------------------------------------
def build_parser() -> argparse.ArgumentParser:
    """The ``scoutsim`` argument parser (subcommands ``run`` and ``basin``)."""
    from . import __version__
    parser = argparse.ArgumentParser(
        prog="scoutsim",
        description="Simulate planar Scout II bounding (Poulakakis, Smith & Buehler, ICRA 2004).",
        epilog="examples:\n"
               "  scoutsim run                       # Model II, 10 s, results in scoutsim_out/\n"
               "  scoutsim run --model I --duration 5 --robot my_robot.toml --out out_I\n"
               "  scoutsim run --json --no-plots     # summary as JSON on stdout\n"
               "  scoutsim basin --model I,II --speeds 1.0,1.3 --pitch-rates -50,0 --workers 4\n"
               "  scoutsim compare run1.csv run2.csv --models I,II --out cmp\n"
               "  scoutsim compare --example             # on the shipped SYNTHETIC data set\n"
               "  scoutsim plot scoutsim_out/result.npz --out run.pdf --t0 3 --t1 4\n"
               "  scoutsim animate scoutsim_out/result.npz --out run.gif --t0 3 --t1 4",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"scoutsim {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="{run,basin,compare,plot,animate,orbit,sweep,identify,rig}")

    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--duration", type=_positive_float, default=10.0, metavar="S",
                        help="simulated time per run [s] (default: 10)")
    common.add_argument("--robot", metavar="FILE",
                        help="TOML robot/controller file with the layout of "
                             "scoutsim/data/scout2.toml; unset entries keep the Scout II "
                             "defaults")
    common.add_argument("--out", default="scoutsim_out", metavar="DIR",
                        help="output directory, created if needed (default: scoutsim_out)")
    common.add_argument("--rtol", type=_positive_float, default=None, metavar="X",
                        help="integrator relative tolerance (default: 1e-8)")
    common.add_argument("--atol", type=_positive_float, default=None, metavar="X",
                        help="integrator absolute tolerance (default: 1e-9)")
    common.add_argument("--friction", type=_friction, default=SCOUT_FLOOR_FRICTION, metavar="MU",
                        help="Coulomb friction coefficient of the toes (default: "
                             f"{SCOUT_FLOOR_FRICTION}, rubber toes on carpet, where the "
                             "paper's experiments ran; 'inf' = no slip; see docs/model.md)")
    common.add_argument("--no-progress", action="store_true",
                        help="no progress bar (it is also off when stderr is not a terminal)")

    run = sub.add_parser(
        "run", parents=[common], help="simulate one run, print a summary, write data and plots",
        description="Simulate one bounding run and write to DIR: timeseries.csv, result.npz, "
                    "summary.json, run.png and torque_speed.png.")
    run.add_argument("--model", choices=MODELS, default="II",
                     help="actuator/transmission model (default: II)")
    run.add_argument("--speed", type=_finite_float, default=None, metavar="V",
                     help="initial forward speed [m/s] (default: 1.2)")
    run.add_argument("--height", type=_positive_float, default=None, metavar="Y",
                     help="initial torso COM height [m] (default: 0.33)")
    run.add_argument("--pitch-rate", type=_finite_float, default=None, metavar="W",
                     help="initial pitch rate [deg/s] (default: 0)")
    run.add_argument("--no-plots", action="store_true", help="do not write run.png and "
                     "torque_speed.png")
    run.add_argument("--json", action="store_true",
                     help="print the summary as JSON on stdout instead of the table")
    run.set_defaults(func=_cmd_run)

    basin = sub.add_parser(
        "basin", parents=[common],
        help="basin map: which starts reach steady bounding, per model and floor",
        description="Run a grid of initial states (forward speed x pitch rate x height; "
                    "level torso, legs at their touchdown angles) for each model and floor in "
                    "parallel and report the fraction that reaches steady bounding "
                    "(GaitMetrics.is_steady_bounding: completed, >= 7 steady strides after "
                    "the 2 s transient, stride-period CV <= 5 %%) and the cycle's speed. "
                    "Starts with a toe below the ground are recorded as invalid_start and "
                    "left out of the fraction. Writes basin.csv, basin.json and the map "
                    "basin.png to DIR.")
    basin.add_argument("--model", type=_model_list, default=["ideal", "I", "II"], metavar="LIST",
                       help="comma-separated models (default: ideal,I,II)")
    basin.add_argument("--floors", type=_friction_list, default=None, metavar="LIST",
                       help="comma-separated toe friction coefficients, 'inf' = no slip "
                            f"(default: {SCOUT_FLOOR_FRICTION:g},inf; --friction MU runs one)")
    basin.add_argument("--speeds", type=_float_list(), default=list(DEFAULT_SPEEDS),
                       metavar="LIST", help="initial forward speeds [m/s] (default: "
                       + ",".join(f"{v:g}" for v in DEFAULT_SPEEDS) + ")")
    basin.add_argument("--pitch-rates", type=_float_list(), default=list(DEFAULT_PITCH_RATES),
                       metavar="LIST", help="initial pitch rates [deg/s], positive = nose "
                       "rising (default: " + ",".join(f"{v:g}" for v in DEFAULT_PITCH_RATES)
                       + ")")
    basin.add_argument("--heights", type=_float_list(positive=True), default=list(DEFAULT_HEIGHTS),
                       metavar="LIST", help="initial torso COM heights [m] (default: "
                       + ",".join(f"{v:g}" for v in DEFAULT_HEIGHTS) + ")")
    basin.add_argument("--no-plots", action="store_true", help="do not write basin.png")
    basin.add_argument("--workers", type=_positive_int, default=None, metavar="N",
                       help="parallel processes (default: os.cpu_count(); 1 runs in this "
                            "process)")
    basin.set_defaults(func=_cmd_basin)

    compare = sub.add_parser(
        "compare", help="Fig. 12 errors of the models against experiment logs",
        description="Split each experiment log into strides (back-leg lift-off to the next), "
                    "simulate each model and measure it through the same chain (lasers, "
                    "15 Hz FFT low-pass, controller leg states), and report the percent "
                    "error of stride frequency, duty factors, pitch and height extremes: each "
                    "experimental steady stride against the model's mean steady stride, mean "
                    "and max over all strides of all runs (paper Fig. 12). Writes errors.csv, "
                    "errors_detail.csv and errors.md to DIR. Log format: docs/validation.md.")
    compare.add_argument("logs", nargs="*", metavar="LOG",
                         help="experiment log files (.csv, .csv.gz, .parquet) or directories "
                              "of them")
    compare.add_argument("--example", action="store_true",
                         help="use the shipped example data set (SYNTHETIC: generated by "
                              "scoutsim with perturbed parameters and sensor noise, not "
                              "robot data)")
    compare.add_argument("--models", type=_model_list, default=["ideal", "I", "II"],
                         metavar="LIST", help="comma-separated models (default: ideal,I,II)")
    compare.add_argument("--duration", type=_positive_float, default=None, metavar="S",
                         help="simulated time per model [s] (default: the longest log, at "
                              "least 10)")
    compare.add_argument("--robot", metavar="FILE",
                         help="TOML robot/controller file for the simulations (layout of "
                              "scoutsim/data/scout2.toml)")
    compare.add_argument("--out", default="scoutsim_out", metavar="DIR",
                         help="output directory, created if needed (default: scoutsim_out)")
    compare.add_argument("--friction", type=_friction, default=SCOUT_FLOOR_FRICTION,
                         metavar="MU", help="Coulomb friction coefficient of the simulated "
                         f"toes (default: {SCOUT_FLOOR_FRICTION})")
    compare.add_argument("--transient", type=_finite_float, default=2.0, metavar="S",
                         help="strides starting earlier than this after the start of a record "
                              "are transient [s] (default: 2)")
    compare.add_argument("--no-progress", action="store_true",
                         help="no progress bar (it is also off when stderr is not a terminal)")
    compare.add_argument("--no-plots", action="store_true",
                         help="do not write the figures (fig5, fig8-fig12, phase .png) and "
                              "phase_rms.csv")
    compare.set_defaults(func=_cmd_compare)

    plot = sub.add_parser(
        "plot", help="figure of one saved run (result.npz) or one experiment log",
        description="Plot one run: a result.npz written by `scoutsim run` (pitch, height, "
                    "leg angles with leg states, hip torques) or an experiment log (.csv, "
                    ".csv.gz, .parquet: measured pitch and height, leg angles, leg states, "
                    "torques from current).")
    plot.add_argument("input", metavar="RESULT.npz|LOG", help="saved result or experiment log")
    plot.add_argument("--out", metavar="FILE", default=None,
                      help="output figure, .png, .pdf or .svg (default: INPUT's name with "
                           ".png, in the current directory)")
    plot.add_argument("--t0", type=_finite_float, default=None, metavar="S",
                      help="start of the time window [s]")
    plot.add_argument("--t1", type=_finite_float, default=None, metavar="S",
                      help="end of the time window [s]")
    plot.set_defaults(func=_cmd_plot)

    anim = sub.add_parser(
        "animate", help="stick-figure animation of a saved run (GIF or MP4)",
        description="Animate a result.npz written by `scoutsim run`: torso box, legs "
                    "coloured by controller leg state, ground-force arrows, ground line, "
                    "time stamp. Frames at t0 + k/fps, k = 0 .. floor((t1 - t0) fps). GIF "
                    "via Pillow; MP4 needs ffmpeg on the PATH.")
    anim.add_argument("input", metavar="RESULT.npz", help="saved result (scoutsim run --out)")
    anim.add_argument("--out", metavar="FILE", required=True, help="output .gif or .mp4")
    anim.add_argument("--fps", type=_positive_float, default=25.0, metavar="N",
                      help="frames per simulated second, played back in real time "
                           "(default: 25)")
    anim.add_argument("--t0", type=_finite_float, default=None, metavar="S",
                      help="start of the animated window [s] (default: start of the run)")
    anim.add_argument("--t1", type=_finite_float, default=None, metavar="S",
                      help="end of the animated window [s] (default: end of the run)")
    anim.add_argument("--dpi", type=_positive_int, default=80, metavar="N",
                      help="resolution; frames are 8 x 4 inches (default: 80 -> 640 x 320)")
    anim.set_defaults(func=_cmd_animate)

    orbit = sub.add_parser(
        "orbit", help="periodic bounding orbit and its Floquet multipliers (docs/orbits.md)",
        description="--passive: the conservative massless-leg model's periodic bound through "
                    "a level-torso apex of the given speed, height and pitch rate; solves for "
                    "the touchdown angles (from the world vertical) and prints them, the "
                    "period, the multipliers of the apex return map and the map residual. "
                    "Without --passive: the controlled robot's periodic orbit (Newton on the "
                    "stride map sampled where the controller detects back-leg lift-off, "
                    "started from a converged run), its touchdown angles from the world "
                    "vertical, period, Floquet multipliers and residual.")
    orbit.add_argument("--passive", action="store_true",
                       help="the passive conservative model (massless legs, SPEC.md 2)")
    orbit.add_argument("--speed", type=_positive_float, default=1.3, metavar="V",
                       help="--passive: forward speed at the apex [m/s] (default: 1.3)")
    orbit.add_argument("--apex-height", type=_positive_float, default=0.35, metavar="H",
                       help="--passive: torso COM height at the apex [m] (default: 0.35)")
    orbit.add_argument("--pitch-rate", type=_finite_float, default=0.0, metavar="W",
                       help="--passive: pitch rate at the apex [deg/s] (default: 0)")
    orbit.add_argument("--model", choices=("ideal", "I", "II"), default="II",
                       help="controlled model (default: II)")
    orbit.add_argument("--friction", type=_friction, default=SCOUT_FLOOR_FRICTION,
                       metavar="MU", help=f"controlled: toe friction (default: "
                       f"{SCOUT_FLOOR_FRICTION})")
    orbit.add_argument("--duration", type=_positive_float, default=12.0, metavar="S",
                       help="controlled: simulated time to the Newton start [s] (default: 12)")
    orbit.add_argument("--json", action="store_true", help="print one JSON object")
    orbit.set_defaults(func=_cmd_orbit)

    sw = sub.add_parser(
        "sweep", parents=[common],
        help="parameter sweep (grid or random sample) in parallel or on a Dask cluster",
        description="Run a grid or random sample of robot/controller parameters, named "
                    "robot.<field> or controller.<field> (SI units as in RobotParameters / "
                    "ControllerParameters; a _deg suffix on an angle field takes degrees), "
                    "and write sweep.parquet, sweep.csv, the checkpoint points.jsonl (an "
                    "interrupted sweep resumes) and, for a two-parameter grid, map.png. "
                    "Example: scoutsim sweep --grid controller.touchdown_angle_front_deg="
                    "15:27:20 --grid controller.touchdown_angle_back_deg=13:25:20 "
                    "--duration 2")
    sw.add_argument("--grid", action="append", default=[], metavar="NAME=START:STOP:NUM",
                    help="grid axis (repeatable): NUM values from START to STOP")
    sw.add_argument("--random", action="append", default=[], metavar="NAME=LOW:HIGH",
                    help="uniformly sampled parameter (repeatable), with --samples")
    sw.add_argument("--samples", type=_positive_int, default=100, metavar="N",
                    help="number of random points (default: 100)")
    sw.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    sw.add_argument("--model", choices=("ideal", "I", "II"), default="II",
                    help="model (default: II)")
    sw.add_argument("--workers", type=_positive_int, default=None, metavar="N",
                    help="local processes (default: all cores)")
    sw.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="Dask distributed scheduler address (e.g. tcp://host:8786)")
    sw.add_argument("--no-resume", action="store_true",
                    help="recompute every point even if DIR/points.jsonl has it")
    sw.add_argument("--orbit", action="store_true",
                    help="also find each bounding point's periodic orbit (Newton) and record "
                         "its period and Floquet stability (a few s per point)")
    sw.set_defaults(func=_cmd_sweep)
    _add_identification_parsers(sub)
    return parser


def _sweep_axis(text: str, n_parts: int):
    """'name=a:b[:n]' -> (SI name, floats); a _deg suffix converts degrees once, here."""
    name, sep, rng = text.partition("=")
    parts = rng.split(":")
    if not sep or len(parts) != n_parts:
        form = "NAME=START:STOP:NUM" if n_parts == 3 else "NAME=LOW:HIGH"
        raise _UsageError(f"{text!r} is not allowed: must be {form}")
    try:
        vals = [float(v) for v in parts]
    except ValueError:
        raise _UsageError(f"{text!r}: the range must be numbers") from None
    if name.endswith("_deg"):
        name = name[:-4]
        vals = [math.radians(v) for v in vals[:2]] + vals[2:]
    return name, vals


def _cmd_sweep(args) -> int:
    import numpy as np
    from .analysis.sweep import grid_points, random_points, sweep
    if bool(args.grid) == bool(args.random):
        raise _UsageError("give either --grid axes or --random parameters")
    try:
        if args.grid:
            axes = {}
            for g in args.grid:
                name, (a, b, n) = _sweep_axis(g, 3)
                if n < 1 or n != int(n):
                    raise _UsageError(f"{g!r}: NUM must be a whole number >= 1")
                axes[name] = np.linspace(a, b, int(n))
            points = grid_points(axes)
        else:
            bounds = {}
            for g in args.random:
                name, (a, b) = _sweep_axis(g, 2)
                bounds[name] = (a, b)
            points = random_points(bounds, args.samples, args.seed)
    except ValueError as exc:
        raise _UsageError(str(exc)) from None
    robot, controller = _load_parameters(args.robot)
    out = _out_dir(args.out)
    progress = (not args.no_progress) and sys.stderr.isatty()
    wall0 = time.perf_counter()
    res = sweep(points, model=args.model, duration=args.duration, robot=robot,
                controller=controller, friction_coefficient=args.friction, out=out,
                workers=args.workers, scheduler=args.scheduler, progress=progress,
                resume=not args.no_resume, orbit=args.orbit)
    wall = time.perf_counter() - wall0
    outcomes = {}
    for r in res.rows:
        outcomes[r["outcome"]] = outcomes.get(r["outcome"], 0) + 1
    steady = sum(bool(r.get("steady_bounding")) for r in res.rows)
    print(f"scoutsim sweep: {len(points)} points of model {args.model}, {args.duration:g} s "
          f"each ({res.settings['n_resumed']} resumed from {out}/points.jsonl)")
    print("  outcomes: " + ", ".join(f"{k} {v}" for k, v in sorted(outcomes.items())))
    print(f"  steady bounding: {steady}")
    print(f"  wall time {wall:.1f} s; wrote sweep.parquet, sweep.csv to {out}/")
    if args.grid and len(res.parameters) == 2:
        res.plot_map(res.parameters[0], res.parameters[1], "average_speed_m_s",
                     path=out / "map.png")
        print(f"  map of the average speed: {out}/map.png")
        if args.orbit:
            res.plot_map(res.parameters[0], res.parameters[1], "orbit_spectral_radius",
                         path=out / "stability.png")
            print(f"  map of the orbit's spectral radius (< 1: stable): {out}/stability.png")
    if args.orbit:
        stable = sum(bool(r.get("orbit_stable")) for r in res.rows)
        print(f"  periodic orbits found and stable: {stable} of {steady} bounding points")
    errors = [r for r in res.rows if r["outcome"] == "error"]
    for r in errors[:3]:
        print(f"scoutsim sweep: point {({k: r[k] for k in res.parameters})} failed: "
              f"{r['error']}", file=sys.stderr)
    return 0


def main(argv=None) -> int:
    """Entry point of the ``scoutsim`` console script; returns the exit code."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    try:
        args = parser.parse_args(_join_list_values(argv))
        # (basin: a floor given with --friction replaces the default pair of floors)
        args.friction_given = any(a == "--friction" or a.startswith("--friction=") for a in argv)
    except SystemExit as exc:  # --help, --version or a usage error (argparse printed it)
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    if args.command is None:
        parser.print_help()
        return 0
    try:
        return args.func(args)
    except _UsageError as exc:
        print(f"scoutsim {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"scoutsim {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `scoutsim run --json | head`
        try:  # keep Python from complaining again when it flushes stdout at exit
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except (OSError, ValueError, AttributeError):
            pass
        return 1


# -----------------------------------------------------------------------------------------
# helpers
# -----------------------------------------------------------------------------------------
def _load_parameters(path):
    """(robot, controller) from the user's TOML file (or the defaults); _UsageError if bad."""
    from .parameters import load_parameters
    if path is not None:
        p = Path(path)
        if not p.exists():
            raise _UsageError(f"robot file '{path}' not found")
        if not p.is_file():
            raise _UsageError(f"robot file '{path}' is not a file")
    try:
        return load_parameters(path)
    except OSError as exc:
        raise _UsageError(f"cannot read robot file '{path}': {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise _UsageError(f"robot file '{path}' is not UTF-8 text: {exc}") from None
    except ValueError as exc:  # ParameterError (names the field) and other bad values
        raise _UsageError(str(exc)) from None


def _integrator(args):
    from .simulation import IntegratorSettings
    kw = {}
    if args.rtol is not None:
        kw["rtol"] = args.rtol
    if args.atol is not None:
        kw["atol"] = args.atol
    try:
        return IntegratorSettings(**kw)
    except ValueError as exc:
        raise _UsageError(str(exc)) from None


def _out_dir(path) -> Path:
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _UsageError(f"cannot create output directory '{out}': {exc.strerror or exc}") from None
    return out


def _json_safe(v):
    """Replace non-finite floats by None (strict JSON has no NaN / Infinity)."""
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, dict):
        return {k: _json_safe(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_json_safe(x) for x in v]
    return v


def _dumps(obj) -> str:
    return json.dumps(_json_safe(obj), indent=2, allow_nan=False)


def column_unit(name: str) -> str | None:
    """Unit of a ``result.columns()`` name (None for codes and unknown names)."""
    for prefix, unit, exact in TIMESERIES_UNITS:
        if (name == prefix) if exact else name.startswith(prefix):
            return unit
    return None


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


# -----------------------------------------------------------------------------------------
# scoutsim run
# -----------------------------------------------------------------------------------------
def _cmd_run(args) -> int:
    from .simulation import InitialState, simulate
    robot, controller = _load_parameters(args.robot)
    integ = _integrator(args)
    changes = {}
    if args.speed is not None:
        changes["dx"] = args.speed
    if args.height is not None:
        changes["y"] = args.height
    if args.pitch_rate is not None:
        changes["dtheta"] = math.radians(args.pitch_rate)
    init = InitialState(**changes)
    out = _out_dir(args.out)
    progress = (not args.no_progress) and sys.stderr.isatty()

    wall0 = time.perf_counter()
    try:
        result = simulate(robot, controller, init, args.duration, model=args.model,
                          integrator=integ, friction_coefficient=args.friction,
                          progress=progress)
    except ValueError as exc:  # invalid initial state or option
        raise _UsageError(str(exc)) from None
    wall = time.perf_counter() - wall0

    summary = result.summary()
    files = [out / "timeseries.csv", out / "result.npz", out / "summary.json"]
    write_timeseries_csv(result, files[0])
    result.save(files[1])
    files[2].write_text(_dumps(summary) + "\n")
    if not args.no_plots:
        from .plotting import plot_run, plot_torque_speed
        plot_run(result, out / "run.png")
        plot_torque_speed(result, "both", out / "torque_speed.png")
        files += [out / "run.png", out / "torque_speed.png"]

    if args.json:
        print(_dumps(summary))
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


# -----------------------------------------------------------------------------------------
# scoutsim basin
# -----------------------------------------------------------------------------------------
def format_basin(per: dict, n_grid: int, duration: float) -> str:
    """The human-readable basin table (one row per model and floor)."""
    head = ("model", "floor", "starts", "invalid", "valid", "steady", "fraction", "fell",
            "other", "cycle m/s")
    lines = [f"scoutsim basin: {n_grid} starts per model and floor, {duration:g} s each; "
             "fraction = steady bounding / valid starts; cycle m/s = median speed of the "
             "starts that bound",
             "  " + "  ".join(f"{h:>9}" for h in head)]
    for key, s in per.items():
        frac = s["fraction_steady_bounding"]
        fell = s["outcomes"].get("fell", 0)
        other = s["n_valid"] - s["outcomes"].get("completed", 0) - fell
        v = s.get("median_cycle_speed_m_s")
        mu = s.get("friction")
        vals = (s.get("model", key), "-" if mu is None else floor_label(mu), s["n_starts"],
                s["n_invalid_start"], s["n_valid"], s["n_steady_bounding"],
                "n/a" if frac is None else f"{frac:.3f}", fell, other,
                "-" if v is None else f"{v:.3f}")
        lines.append("  " + "  ".join(f"{x!s:>9}" for x in vals))
    return "\n".join(lines)


def _cmd_basin(args) -> int:
    robot, controller = _load_parameters(args.robot)
    integ = _integrator(args)
    out = _out_dir(args.out)
    models = args.model
    workers = args.workers or os.cpu_count() or 1
    progress = (not args.no_progress) and sys.stderr.isatty()
    grid = [(v, w, h) for v in args.speeds for w in args.pitch_rates for h in args.heights]
    floors = (args.floors if args.floors is not None else
              [args.friction] if getattr(args, "friction_given", False) else list(DEFAULT_FLOORS))
    tasks = basin_tasks(models, floors, args.speeds, args.pitch_rates, args.heights,
                        args.duration, robot, controller, integ)
    if args.duration < 5.0:
        print(f"scoutsim basin: note: --duration {args.duration:g} s is short; steady bounding "
              "needs >= 7 strides after the 2 s transient, so (almost) no start can qualify",
              file=sys.stderr)

    wall0 = time.perf_counter()
    rows = run_basin_tasks(tasks, workers, progress)
    wall = time.perf_counter() - wall0

    csv_path = out / "basin.csv"
    with open(csv_path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=BASIN_COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if r.get(k) is None else r[k]) for k in BASIN_COLUMNS})
    per = basin_stats(rows, models, floors if len(floors) > 1 else None)
    summary = {
        "fraction_steady_bounding": {m: s["fraction_steady_bounding"] for m, s in per.items()},
        "models": per,
        "grid": {"speeds_m_s": args.speeds, "pitch_rates_deg_s": args.pitch_rates,
                 "heights_m": args.heights, "duration_s": args.duration,
                 "floors": ["inf" if math.isinf(mu) else mu for mu in floors],
                 "n_starts_per_model": len(grid)},
        "criterion": "GaitMetrics.is_steady_bounding(): outcome completed, >= 7 steady "
                     "strides after the 2 s transient, stride-period CV <= 0.05; "
                     "invalid_start excluded from the denominator",
        "wall_time_s": wall,
        "workers": workers,
    }
    (out / "basin.json").write_text(_dumps(summary) + "\n")
    written = "basin.csv, basin.json"
    if not args.no_plots:
        from .plotting import plot_basin_map
        from .simulation import InitialState
        d = InitialState()
        plot_basin_map(rows, out / "basin.png", default_start=(d.dx, math.degrees(d.dtheta)))
        written += ", basin.png"

    print(format_basin(per, len(grid), args.duration))
    n_invalid = sum(s["n_invalid_start"] for s in per.values())
    if n_invalid:
        example = next(r for r in rows if r["outcome"] == "invalid_start")
        print(f"{n_invalid} invalid start(s) (toe below the ground), e.g. speed "
              f"{example['speed']:g} m/s, pitch rate {example['pitch_rate_deg_s']:g} deg/s, "
              f"height {example['height']:g} m: {example.get('error', '')}")
    print(f"wall time {wall:.1f} s with {min(workers, len(tasks))} worker(s); "
          f"wrote {written} to {out}/")
    errors = [r for r in rows if r["outcome"] == "error"]
    for r in errors[:5]:
        print(f"scoutsim basin: start model {r['model']}, speed {r['speed']:g}, pitch rate "
              f"{r['pitch_rate_deg_s']:g}, height {r['height']:g} crashed: {r['error']}",
              file=sys.stderr)
    return 1 if errors else 0



# -----------------------------------------------------------------------------------------
# scoutsim compare
# -----------------------------------------------------------------------------------------
def _cmd_compare(args) -> int:
    from .validation.errors import compare
    from .validation.logs import LogError, load_dataset
    if args.example and args.logs:
        raise _UsageError("give log files or --example, not both")
    if not args.example and not args.logs:
        raise _UsageError("give at least one log file (or --example for the shipped "
                          "synthetic data set)")
    if args.transient < 0:
        raise _UsageError(f"--transient {args.transient:g} is not allowed: must be >= 0")
    if args.example:
        from .validation.make_example import example_paths
        paths = example_paths()
    else:
        paths = args.logs
    try:
        logs = load_dataset(paths)
    except LogError as exc:
        raise _UsageError(str(exc)) from None
    robot, controller = _load_parameters(args.robot)
    out = _out_dir(args.out)
    progress = (not args.no_progress) and sys.stderr.isatty()
    wall0 = time.perf_counter()
    try:
        table = compare(logs, models=args.models, robot=robot, controller=controller,
                        duration=args.duration, friction_coefficient=args.friction,
                        transient_s=args.transient, progress=progress)
    except ValueError as exc:
        raise _UsageError(str(exc)) from None
    wall = time.perf_counter() - wall0
    table.to_csv(out / "errors.csv")
    table.to_detail_csv(out / "errors_detail.csv")
    (out / "errors.md").write_text(table.to_markdown())
    print(table.format())
    written = ["errors.csv", "errors_detail.csv", "errors.md"]
    if not args.no_plots:
        from .validation.figures import write_figures
        from .validation.phase import phase_compare
        figs = write_figures(logs, table, out, transient_s=args.transient)
        written += [p.name for p in figs.values()]
        print()
        print(phase_compare(logs, table, transient_s=args.transient).format())
    print(f"wall time {wall:.1f} s; wrote {', '.join(written)} to {out}/")
    failed = [m for m, r in table.models.items() if r.outcome == "numerical_failure"]
    return 1 if failed else 0


# -----------------------------------------------------------------------------------------
# scoutsim plot / scoutsim animate
# -----------------------------------------------------------------------------------------
def _input_file(path: str) -> Path:
    p = Path(path)
    if not p.exists():
        raise _UsageError(f"input '{path}' not found")
    if not p.is_file():
        raise _UsageError(f"input '{path}' is not a file")
    return p


def _load_result(p: Path):
    from .result import SimulationResult
    if p.suffix.lower() != ".npz":
        raise _UsageError(f"input '{p}' is not a saved result: expected a .npz written by "
                          "`scoutsim run` (result.npz)")
    try:
        return SimulationResult.load(p)
    except (OSError, ValueError, KeyError) as exc:
        raise _UsageError(f"cannot read result '{p}': {exc}") from None


def _window(args):
    if args.t0 is not None and args.t1 is not None and not args.t1 > args.t0:
        raise _UsageError(f"--t0 {args.t0:g} --t1 {args.t1:g} is not allowed: need t1 > t0")


def _cmd_plot(args) -> int:
    from .validation.logs import LOG_SUFFIXES, LogError, load_log
    p = _input_file(args.input)
    _window(args)
    name = p.name.lower()
    is_log = any(name.endswith(s) for s in LOG_SUFFIXES)
    if not is_log and p.suffix.lower() != ".npz":
        raise _UsageError(f"input '{p}' is neither a saved result (.npz) nor an experiment log "
                          f"({', '.join(LOG_SUFFIXES)})")
    if args.out is None:
        stem = p.name
        for s in (".npz",) + LOG_SUFFIXES:
            if stem.lower().endswith(s):
                stem = stem[:-len(s)]
                break
        out = Path(f"{stem}.png")
    else:
        out = Path(args.out)
    if out.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise _UsageError(f"--out '{out}' is not allowed: the suffix must be .png, .pdf or "
                          ".svg")
    if is_log:
        try:
            obj = load_log(p)
        except LogError as exc:
            raise _UsageError(str(exc)) from None
        t = obj.t
    else:
        obj = _load_result(p)
        t = obj.t
    t0 = float(t[0]) if args.t0 is None else args.t0
    t1 = float(t[-1]) if args.t1 is None else args.t1
    t_range = None if (args.t0 is None and args.t1 is None) else (t0, t1)
    try:
        if is_log:
            from .validation.figures import plot_log
            plot_log(obj, out, t_range=t_range)
        else:
            from .plotting import plot_run
            plot_run(obj, out, t_range=t_range)
    except ValueError as exc:
        raise _UsageError(str(exc)) from None
    print(f"wrote {out}")
    return 0


def _cmd_animate(args) -> int:
    from .animation import ANIMATION_SUFFIXES, save_animation
    p = _input_file(args.input)
    _window(args)
    out = Path(args.out)
    if out.suffix.lower() not in ANIMATION_SUFFIXES:
        raise _UsageError(f"--out '{out}' is not allowed: the suffix must be .gif or .mp4")
    result = _load_result(p)
    try:
        save_animation(result, out, fps=args.fps, t0=args.t0, t1=args.t1, dpi=args.dpi)
    except (ValueError, RuntimeError) as exc:
        raise _UsageError(str(exc)) from None
    print(f"wrote {out}")
    return 0


# -----------------------------------------------------------------------------------------
# scoutsim orbit
# -----------------------------------------------------------------------------------------
def _cmd_orbit(args) -> int:
    from .analysis.orbits import MapError, controlled_fixed_point, passive_bounding_orbit
    if args.passive:
        try:
            orb = passive_bounding_orbit(args.speed, args.apex_height,
                                         math.radians(args.pitch_rate))
        except MapError as exc:
            print(f"scoutsim orbit: {exc}", file=sys.stderr)
            return 1
        d = orb.to_dict()
        if args.json:
            print(_dumps(d))
            return 0
        print(f"scoutsim orbit: passive model, apex speed {args.speed:g} m/s, height "
              f"{args.apex_height:g} m, pitch rate {args.pitch_rate:g} deg/s, torso level")
        print(f"  touchdown angle back / front  {d['touchdown_angle_back_deg']:.6f} / "
              f"{d['touchdown_angle_front_deg']:.6f} deg (from the world vertical)")
        print(f"  period                        {d['period_s']:.6f} s")
        print("  eigenvalues                   " + ", ".join(
            f"{m.real:.6f}{m.imag:+.6f}j" for m in orb.multipliers)
              + f"  (|.| = {', '.join(f'{abs(m):.4f}' for m in orb.multipliers)})")
        print(f"  residual max|P(z)-z|          {d['residual']:.2e}")
        return 0
    try:
        orb = controlled_fixed_point(model=args.model, friction_coefficient=args.friction,
                                     settle_duration=args.duration)
    except MapError as exc:
        print(f"scoutsim orbit: {exc}", file=sys.stderr)
        return 1
    d = orb.to_dict()
    if args.json:
        print(_dumps(d))
        return 0
    print(f"scoutsim orbit: model {args.model}, Table I controller at 1 kHz, mu = "
          f"{args.friction:g}; section: the sample at which the controller detects back-leg "
          "lift-off; Newton on the sampled stride map")
    print(f"  touchdown angle back / front  {d['touchdown_angle_back_deg']:.4f} / "
          f"{d['touchdown_angle_front_deg']:.4f} deg (from the world vertical, on the orbit)")
    print(f"  period                        {d['period_s']:.6f} s "
          f"({round(d['period_s'] * 1000)} control periods), mean speed "
          f"{d['mean_speed_m_s']:.4f} m/s")
    for name, v in d["state"].items():
        print(f"    {name:<18} {v: .9f}")
    import numpy as np
    mags = np.abs(orb.multipliers)
    big = np.argsort(-mags)[:6]
    print("  largest multipliers           " + ", ".join(
        f"{orb.multipliers[i].real:.4f}{orb.multipliers[i].imag:+.4f}j" for i in big)
          + f"  (spectral radius {mags.max():.4f}: {'stable' if orb.stable else 'unstable'})")
    print(f"  residual max|P(z)-z|          {d['residual']:.2e} after {d['iterations']} "
          "Newton iterations")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())


# -----------------------------------------------------------------------------------------
# scoutsim identify / scoutsim rig (issue 5, docs/identification.md)
# -----------------------------------------------------------------------------------------
def _add_identification_parsers(sub):
    from .identification.fit import DEFAULT_PARAMS
    from .identification.rigs import HIP_PARAMETERS
    idf = sub.add_parser(
        "identify", help="fit Model II hip-unit parameters to bench-rig logs",
        description="Fit hip-unit parameters (nonlinear least squares with a multi-start "
                    "global search) to free-swing or flight-step rig logs; write DIR/"
                    "identified.json (value, unit, interval, identifiable flag per parameter) "
                    "and fit figures DIR/fit_<n>.png. --example makes virtual logs with known "
                    "parameters and sensor noise, fits them and prints true against fitted "
                    "values. See docs/identification.md.")
    idf.add_argument("logs", nargs="*", metavar="LOG", help="rig log files (CSV/Parquet)")
    idf.add_argument("--example", action="store_true",
                     help="generate virtual logs with known parameters, fit, compare")
    idf.add_argument("--rig", choices=("free-swing", "flight-steps"), default=None,
                     help="the rig that made the logs (default: the logs' metadata 'rig'; "
                          "with --example: both rigs, fitted together)")
    idf.add_argument("--params", default=None, metavar="LIST",
                     help="comma-separated parameters to fit, from: "
                          + ", ".join(HIP_PARAMETERS) + " (default: "
                          + ", ".join(DEFAULT_PARAMS["free-swing"]) + ")")
    idf.add_argument("--robot", metavar="FILE",
                     help="TOML robot file: the starting values and the fixed parameters")
    idf.add_argument("--out", default="scoutsim_identify", metavar="DIR",
                     help="output directory (default: scoutsim_identify)")
    idf.add_argument("--starts", type=_positive_int, default=16, metavar="N",
                     help="Sobol start points of the global search (default: 16)")
    idf.add_argument("--local", type=_positive_int, default=2, metavar="N",
                     help="best starts refined by least squares (default: 2)")
    idf.add_argument("--seed", type=int, default=0, help="Sobol / noise seed (default: 0)")
    idf.add_argument("--confidence", type=float, default=0.95, metavar="C",
                     help="interval confidence level (default: 0.95)")
    idf.add_argument("--no-plots", action="store_true", help="do not write fit figures")
    idf.add_argument("--json", action="store_true", help="print identified.json to stdout")
    idf.set_defaults(func=_cmd_identify)

    rg = sub.add_parser(
        "rig", help="run a virtual bench rig and write its log",
        description="Run a virtual bench rig (the same simulator with the torso clamped) and "
                    "write its log (DIR/<rig>.csv.gz) with sensor noise; the stall rig also "
                    "prints the belt deflection at maximum hip torque (the paper's ~8 deg "
                    "check).")
    rg.add_argument("rig", choices=("free-swing", "flight-steps", "stall"))
    rg.add_argument("--motor", choices=("open", "short"), default="open",
                    help="free swing: motor leads open or shorted (default: open)")
    rg.add_argument("--toe-mass", type=_positive_float, default=None, metavar="KG",
                    help="free swing: mass at the toe [kg] (default: 1)")
    rg.add_argument("--release", default=None, metavar="BACK,FRONT",
                    help="free swing: release angles [deg] (default: 60,-40)")
    rg.add_argument("--duration", type=_positive_float, default=None, metavar="S",
                    help="recorded time [s] (default: the rig's)")
    rg.add_argument("--robot", metavar="FILE", help="TOML robot file (default: Scout II)")
    rg.add_argument("--out", default="scoutsim_rig", metavar="DIR",
                    help="output directory (default: scoutsim_rig)")
    rg.add_argument("--seed", type=int, default=0, help="noise seed (default: 0)")
    rg.add_argument("--no-noise", action="store_true", help="write the noise-free signals")
    rg.set_defaults(func=_cmd_rig)


def _cmd_identify(args) -> int:
    from .identification.fit import EXAMPLE_FACTORS, example_logs, identify
    from .validation.logs import LogError
    if args.example and args.logs:
        raise _UsageError("give log files or --example, not both")
    if not args.example and not args.logs:
        raise _UsageError("give at least one rig log (or --example)")
    if not 0.0 < args.confidence < 1.0:
        raise _UsageError(f"--confidence {args.confidence:g} is not allowed: must be in (0, 1)")
    params = None
    if args.params:
        params = [p.strip() for p in args.params.split(",") if p.strip()]
    robot = None
    if args.robot:
        robot, _ = _load_parameters(args.robot)
    out = _out_dir(args.out)
    wall0 = time.perf_counter()
    try:
        if args.example:
            rigs = (args.rig,) if args.rig else ("free-swing", "flight-steps")
            print("scoutsim identify --example: virtual logs of the " + " and ".join(rigs)
                  + " rig(s), made with a hip unit = Table II x "
                  + ", ".join(f"{k} {v:g}" for k, v in EXAMPLE_FACTORS.items())
                  + "; the fit starts from Table II")
            logs = example_logs(rigs, seed=args.seed, out_dir=out)
            rig = None
        else:
            logs = args.logs
            rig = args.rig
        res = identify(logs, params, rig=rig, robot=robot, n_starts=args.starts,
                       n_local=args.local, seed=args.seed, confidence=args.confidence)
    except LogError as exc:
        raise _UsageError(str(exc)) from None
    except ValueError as exc:
        raise _UsageError(str(exc)) from None
    wall = time.perf_counter() - wall0
    path = res.save(out, figures=not args.no_plots)
    if args.json:
        print(path.read_text())
    else:
        print(res.report())
        print(f"wall time {wall:.1f} s ({res.nfev} rig simulations); wrote {path}"
              + ("" if args.no_plots else " and fit figures") + f" to {out}/")
    return 0


def _cmd_rig(args) -> int:
    from .identification.rigs import (FlightSteps, FreeSwing, RigNoise, Stall, rig_log,
                                      run_rig, stall_deflection)
    robot = None
    if args.robot:
        robot, _ = _load_parameters(args.robot)
    out = _out_dir(args.out)
    kw = {} if args.duration is None else {"duration": args.duration}
    try:
        if args.rig == "free-swing":
            if args.toe_mass is not None:
                kw["toe_mass"] = args.toe_mass
            if args.release:
                try:
                    b, f = (math.radians(float(v)) for v in args.release.split(","))
                except ValueError:
                    raise _UsageError(f"--release {args.release!r} is not allowed: must be "
                                      "BACK,FRONT in degrees") from None
                kw |= {"release_angle_back": b, "release_angle_front": f}
            rig = FreeSwing(motor=args.motor, **kw)
        elif args.rig == "flight-steps":
            rig = FlightSteps(**kw)
        else:
            rig = Stall(**kw)
    except ValueError as exc:
        raise _UsageError(str(exc)) from None
    if args.rig == "stall":
        d = stall_deflection(robot, rig)
        res = d["result"]
        lo, hi = d["static_band_deg"]
        print(f"stall rig: hip torque {d['torque_nm']:.2f} N m per physical leg (N eta K_T "
              f"i_max); belt deflection after {rig.duration:g} s: "
              f"{d['deflection_final_deg']:.3f} deg (static band of the motor stiction "
              f"{lo:.3f} .. {hi:.3f} deg; creep time constant c_b/k_b = "
              f"{d['creep_time_constant_s']:.3f} s); the paper's bound: about 8 deg")
    else:
        res = run_rig(rig, robot)
    log = rig_log(res, noise=None if args.no_noise else RigNoise(), seed=args.seed)
    path = log.save(out / f"{args.rig}.csv.gz")
    print(f"{args.rig} rig: {res.outcome}, {len(res.t)} samples; wrote {path}")
    return 0
