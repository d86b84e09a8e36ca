"""``scoutsim run``: simulate one bounding run, print a summary table (or JSON) and write
the run's tables and summary (and, on request, figures and the older file formats) to the
output directory.

    scoutsim run [--model {ideal,I,II,passive}] [--duration S] [--robot FILE] [--out DIR]
                 [--start {flight,standing}]
                 [--rtol X] [--atol X] [--friction MU] [--speed V] [--height Y]
                 [--pitch-rate W] [--steps] [--format {parquet,csv}] [--plots] [--csv]
                 [--npz] [--no-progress] [--quiet] [--json] [--energy | --no-energy]

Written to DIR: ``timeseries.parquet`` (every control sample, every signal, with the
outcome, statistics and provenance), ``events.parquet`` (every event with the exact state
before and after its transition), ``summary.json``; ``steps.parquet`` with ``--steps``
(every integrator step); ``.csv.gz`` instead of ``.parquet`` without pyarrow or with
``--format csv``. Every power flow is accounted for unless ``--no-energy``: summary.json
has what the gait costs (``electrical_energy_j``, ``cost_of_transport``, ...,
:data:`scoutsim.analysis.gait.SUMMARY_ENERGY_KEYS`) and the balance (``energy_balance``),
the timeseries table the cumulative energies. ``--plots``: run.png, torque_speed.png
and stride_power.png (power over a steady stride by destination); ``--csv``: the plain
timeseries.csv; ``--npz``: result.npz. :meth:`scoutsim.SimulationResult.load` reads DIR
(or result.npz) back bit for bit.

Exit code 1 if the integration failed numerically, 130 if interrupted (the data so far is
still written); a fall is a completed run (exit 0, the summary says so).
"""

from __future__ import annotations

import math
import signal
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path
from types import SimpleNamespace

from ..io.run_directory import MANIFEST, RunDirectory
from ..result.columns import COLUMN_UNITS, column_unit
from ..simulation.streaming import DEFAULT_KEEP_SECONDS
from ..state import InitialState
from ._common import (
    MODELS,
    UsageError,
    add_controller_option,
    add_duration_option,
    add_plots_option,
    check_expected_time,
    command_wall_time,
    controller_choice,
    dumps,
    finite_float,
    integrator,
    load_parameters,
    load_sensors,
    make_controller,
    out_dir,
    positive_float,
    show_progress,
    usage_errors,
    write_json,
)

NAME = "run"

#: Unit of each ``result.columns()`` name (one home:
#: :data:`scoutsim.result.columns.COLUMN_UNITS`), written into the header of
#: ``timeseries.csv`` as ``name [unit]``.
TIMESERIES_UNITS = COLUMN_UNITS


_DEFAULT_START = InitialState()


def _simulate_default(name: str):
    """The default of :func:`scoutsim.simulate`'s argument ``name`` (its one home)."""
    import inspect

    from ..simulation.simulator import simulate
    return inspect.signature(simulate).parameters[name].default


#: simulated time of a run [s]: simulate()'s default
DEFAULT_DURATION_S = _simulate_default("duration")


def register(sub, common) -> None:
    from ..io.tables import FORMATS
    run = sub.add_parser(
        NAME, parents=[common], help="simulate one run, print a summary, write its tables",
        description="Simulate one bounding run and write to DIR: timeseries and events tables "
                    "(Parquet, or gzip-compressed CSV without pyarrow) and summary.json; "
                    "figures with --plots. SimulationResult.load(DIR) reads the run back.")
    run.add_argument("--model", choices=MODELS, default="II",
                     help="actuator/transmission model (default: II)")
    run.add_argument("--start", choices=("flight", "standing"), default="flight",
                     help="flight (default): released in flight at --speed, --height, "
                          "--pitch-rate; standing: at rest on its four legs, set going by "
                          "the start-up (a step of the back legs, then a push of all four) "
                          "into the Table I bound "
                          "(summary: startup_duration_s)")
    add_duration_option(run, DEFAULT_DURATION_S)
    add_controller_option(run)
    run.add_argument("--speed", type=finite_float, default=None, metavar="V",
                     help=f"initial forward speed [m/s] (default: {_DEFAULT_START.dx:g}; "
                          "passive model: scoutsim.default_initial_state)")
    run.add_argument("--height", type=positive_float, default=None, metavar="Y",
                     help=f"initial torso COM height [m] (default: {_DEFAULT_START.y:g}; "
                          "passive model: higher, so that its hanging legs clear the ground "
                          "by the same margin)")
    run.add_argument("--pitch-rate", type=finite_float, default=None, metavar="W",
                     help="initial pitch rate [deg/s] (default: "
                     f"{math.degrees(_DEFAULT_START.dtheta):g})")
    run.add_argument("--steps", action="store_true",
                     help="also record every integrator step (steps table: time, state, "
                          "plant modes)")
    run.add_argument("--format", choices=FORMATS, default=None,
                     help="format of the tables: parquet (default when pyarrow is "
                          "installed) or csv (gzip-compressed, the default otherwise)")
    add_plots_option(run, False, "run.png (pitch, height, leg angles and states, hip "
                                 "torques; runs over 4 s: an overview and the last strides), "
                                 "torque_speed.png (paper Fig. 11) and, with the energy "
                                 "accounting, stride_power.png (power over the last steady "
                                 "stride by destination)")
    run.add_argument("--csv", action="store_true",
                     help="also write timeseries.csv (plain CSV, one row per sample)")
    run.add_argument("--npz", action="store_true",
                     help="also write result.npz (the whole result in one NumPy file)")
    run.add_argument("--stream", action="store_true",
                     help="write the tables as the run is computed, keeping only its last "
                          "--keep seconds in memory (for runs too long for memory; the "
                          "summary and figures cover the kept end). Chosen by itself when "
                          "the run would not fit in memory")
    run.add_argument("--keep", type=positive_float, default=None, metavar="S",
                     help="with --stream: seconds at the end of the run kept in memory for "
                          f"the summary and figures (default: {DEFAULT_KEEP_SECONDS:g})")
    run.add_argument("--no-size-check", action="store_true",
                     help="skip the checks of the memory and disk space the run needs (and "
                          "do not stream because of them)")
    run.add_argument("--energy", action="store_true",
                     help="also print the whole work-energy balance table (every term, "
                          "the residual)")
    run.add_argument("--no-energy", action="store_true",
                     help="no energy accounting, for a faster run (by default every "
                          "power flow is integrated: electrical energy, copper and "
                          "transmission losses, friction, dampers, impacts, cost of "
                          "transport in summary.json and the energy block; it leaves the "
                          "motion the same and makes the simulation of 10 s of Model II "
                          "1.65x slower)")
    run.add_argument("--json", action="store_true",
                     help="print the summary as JSON on stdout instead of the table")
    run.set_defaults(func=execute)


#: exit status of a run whose outputs could not be written (BSD sysexits EX_IOERR)
EXIT_WRITE_FAILED = 74


def _write_outputs(args, out, result, summary, rd, command, info, interrupted):
    """Write the run's files into ``out`` (``rd``: the streamed run's directory, whose
    tables are written already, or None); the finished RunDirectory."""
    if rd is None:
        rd = RunDirectory(out, command=command, info=info).open()
        for path in result.save_tables(out, fmt=args.format):
            rd.add(path.name)
    else:
        rd.info = info           # (the streamed tables are already written and listed)
    rd.write("summary.json", lambda p: write_json(p, summary))
    if args.csv:
        rd.write("timeseries.csv", lambda p: write_timeseries_csv(result, p))
    if args.npz:
        rd.write("result.npz", lambda p: result.save(p))
    if args.plots:
        from ..presentation.plots import plot_run, plot_torque_speed
        rd.write("run.png", lambda p: plot_run(result, p, overview="auto"))
        rd.write("torque_speed.png", lambda p: plot_torque_speed(result, "both", p))
        if result.energy_series is not None and result.provenance.get("model") != "passive" \
                and any(s.energy_t_start is not None for s in result.strides):
            from ..presentation.plots import plot_stride_power
            rd.write("stride_power.png", lambda p: plot_stride_power(result, p))
    rd.finish(outcome=result.outcome, partial=interrupted)
    return rd


@contextmanager
def _ctrl_c_deferred():
    """While the outputs are written, a first Ctrl-C is held until they are whole (the
    command then exits 130); a second one abandons them (KeyboardInterrupt: the directory
    keeps saying "writing"). Writing a run takes a fraction of its computing."""
    state = SimpleNamespace(asked=False)
    if threading.current_thread() is not threading.main_thread():
        yield state
        return

    def handler(signum, frame):
        if state.asked:
            raise KeyboardInterrupt
        state.asked = True
        print("scoutsim run: writing the outputs; they will be complete in a moment "
              "(Ctrl-C again to abandon them)", file=sys.stderr, flush=True)

    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield state
    finally:
        signal.signal(signal.SIGINT, previous)


def _streamed_write_failed(result, out, rd) -> int:
    """A streamed run whose tables the disk refused: say what the directory kept, mark it
    partial, save the kept end of the run elsewhere."""
    info = result.provenance["stream"]
    print(f"scoutsim run: error: could not write the run's tables to {out}/: "
          f"{info['write_error']}; the run stopped at t = {result.t_end:g} s", file=sys.stderr)
    kept = ", ".join(info["tables_kept"]) or "no table"
    until = info["written_until_s"]
    print(f"scoutsim run: {out}/ keeps {kept}" + (f" (samples up to t = {until:g} s)"
                                                   if until is not None else ""),
          file=sys.stderr)
    try:
        rd.finish(outcome=result.outcome, partial=True)
    except OSError:
        pass                            # (the manifest keeps saying "writing")
    print(_rescue(result, f"the run's last {info['keep_seconds']:g} s"), file=sys.stderr)
    return EXIT_WRITE_FAILED


def _rescue(result, what: str = "the run's data") -> str:
    """Save a run whose output directory failed somewhere else (the system's temporary
    directory, then the home directory): what was computed is not lost. The message."""
    import os
    import tempfile
    name = f"scoutsim_rescued_{os.getpid()}_{int(time.time())}.npz"
    for d in (Path(tempfile.gettempdir()), Path.home()):
        try:
            path = result.save(d / name)
        except OSError:
            continue
        return (f"scoutsim run: {what} saved instead to {path} "
                "(SimulationResult.load reads it)")
    return f"scoutsim run: {what} could not be saved anywhere (no space left?)"


def _stream_choice(args) -> bool:
    """Whether the run streams its tables to disk: asked with --stream, or chosen because
    the run would not fit in memory (said on stderr)."""
    from ..simulation.budgets import check_run_memory
    if args.keep is not None and not args.stream:
        raise UsageError("--keep is only allowed with --stream")
    try:
        if not args.no_size_check:
            check_run_memory(args.duration, record_steps=args.steps)
        fits = True
    except ValueError:
        fits = False
    stream = args.stream or not fits
    if stream and (args.csv or args.npz):
        raise UsageError(f"{'--csv' if args.csv else '--npz'} is not allowed with a streamed "
                         "run (it needs the whole time series in memory): read the streamed "
                         "tables instead (SimulationResult.load(DIR))")
    if stream and not args.stream:
        print(f"scoutsim run: {args.duration:g} s would not fit in memory: streaming the "
              "tables to disk as they are computed (the summary covers the last "
              f"{DEFAULT_KEEP_SECONDS:g} s; see --stream, --keep)", file=sys.stderr)
    return stream


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
    """The human-readable summary table of a run: what the robot did (``behaviour``:
    steady bounding, or what instead, :mod:`scoutsim.analysis.behaviour`), the gait means
    over the steady strides, ``wall_s`` the simulation's wall time [s] (its real-time factor
    is t_end / wall_s), ``load_s`` the time the compiled core took to get ready before it,
    ``command_wall_s`` the whole command's."""
    import textwrap
    outcome = summary.get("outcome")
    if outcome != "completed" and t_end is not None:
        outcome = f"{outcome} at t = {t_end:.3f} s"
    rtf = (t_end / wall_s) if wall_s > 0 and t_end else None
    steady = bool(summary.get("n_steady_strides"))
    speed = _fmt(summary.get("mean_speed_m_s"), ".3f", "m/s")
    if not steady:
        # no steady stride: the run's average instead, said to be one
        average = ((summary.get("behaviour_detail") or {}).get("counts") or {}).get(
            "average_speed_m_s")
        speed = "n/a (no steady stride)" + (
            f"; {average:.3f} m/s averaged over the run" if average is not None else "")
    rows = [
        ("outcome", outcome),
        ("what the robot did", summary.get("behaviour") or "n/a"),
    ]
    n_steady = summary.get("n_steady_strides") or 0
    if steady and summary.get("steady_bounding") is False:
        # a few strides passed the steadiness test, but the run is no steady bound: the
        # means below describe those strides alone, and say so
        rows.append(("gait means below", f"over {n_steady} steady stride"
                     f"{'s' if n_steady != 1 else ''} only (not a steady bound)"))
    rows += [
        ("mean forward speed", speed),
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
        ("steady bounding", {True: "yes", False: "no", None: "n/a"}.get(
            summary.get("steady_bounding"), "n/a")),
    ]
    if "startup_duration_s" in summary:
        rows.append(("start-up (standing to bounding)",
                     _fmt(summary["startup_duration_s"], ".3f", "s") + " (t = 0 to the "
                     "hand-over to the bounding controller)"))
    rows += [
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
    for k, v in rows:
        line = f"  {k:<{width}}  {v}"
        if k == "what the robot did":       # a sentence: wrapped under its column
            lines += textwrap.wrap(line, 100, subsequent_indent=" " * (width + 4),
                                   break_on_hyphens=False)
        else:
            lines.append(line)
    return "\n".join(lines)


def format_energy(summary: dict) -> str:
    """The short energy block of a run's summary (:data:`SUMMARY_ENERGY_KEYS
    <scoutsim.analysis.gait.SUMMARY_ENERGY_KEYS>`): where the electrical energy went over
    the run, and the steady strides' mean power and cost of transport."""
    e = summary.get("electrical_energy_j")
    head = ("  energy, whole run      " + (
        f"electrical {e:.1f} J = copper {summary['copper_loss_j']:.1f} + transmission "
        f"{summary['transmission_loss_j']:.1f} + hip work {summary['hip_work_j']:.1f} J"
        if e is not None else f"hip work {_fmt(summary.get('hip_work_j'), '.1f', 'J')}"))
    rows = [head,
            f"  hip work went to       friction and dampers "
            f"{_fmt(summary.get('friction_loss_j'), '.1f', 'J')}, impacts "
            f"{_fmt(summary.get('impact_loss_j'), '.1f', 'J')}, mechanical energy "
            f"{_fmt(summary.get('mechanical_energy_change_j'), '+.1f', 'J')} (residual "
            f"{_fmt(summary.get('energy_residual_j'), '.2g', 'J')})",
            f"  steady strides         mean electrical power "
            f"{_fmt(summary.get('mean_electrical_power_w'), '.1f', 'W')}, cost of transport "
            f"{_fmt(summary.get('cost_of_transport'), '.3f')}"]
    return "\n".join(rows)


def execute(args) -> int:
    from ..simulation.initial_conditions import default_initial_state
    from ..simulation.simulator import simulate, warm_up
    robot, cparams = load_parameters(args.robot)
    sensors = load_sensors(args.robot, robot)
    law, cparams = controller_choice(args.controller, cparams)
    if args.controller != "table-i" and args.model == "passive":
        raise UsageError(f"--controller {args.controller} is not allowed with --model "
                         "passive (the passive model has no controller)")
    controller = make_controller(law, cparams, robot)
    integ = integrator(args)
    changes = {}
    if args.speed is not None:
        changes["dx"] = args.speed
    if args.height is not None:
        changes["y"] = args.height
    if args.pitch_rate is not None:
        changes["dtheta"] = math.radians(args.pitch_rate)
    # the model's default start (the passive model's is higher: its legs hang at the
    # passive touchdown angles), with the options given
    init: InitialState | str = default_initial_state(args.model, robot).replace(**changes)
    if args.start == "standing":
        if changes:
            raise UsageError("--speed, --height and --pitch-rate are only allowed with "
                             "--start flight (a standing robot is at rest)")
        if args.model == "passive":
            raise UsageError("--start standing is not allowed with --model passive (no "
                             "actuator holds or sets going the standing robot)")
        if not isinstance(controller, type(cparams)):
            raise UsageError(f"--start standing is not allowed with --controller "
                             f"{args.controller}: the start-up hands over to the Table I "
                             "controller")
        init = "standing"
    out = out_dir(args.out)
    progress = show_progress(args)

    if args.energy and args.no_energy:
        raise UsageError("--energy and --no-energy are not allowed together")
    energy = not args.no_energy
    check_expected_time(args, {args.model: args.duration})
    stream = _stream_choice(args)
    load_s = warm_up()
    command = " ".join(["scoutsim"] + sys.argv[1:])
    info = {"model": args.model, "controller": args.controller, "duration_s": args.duration,
            "streamed": stream}
    # a streamed run's directory is entered when its first rows arrive (streaming.RunStream)
    rd = RunDirectory(out, command=command, info=info) if stream else None
    wall0 = time.perf_counter()
    with usage_errors():  # invalid initial state or option
        result = simulate(robot, controller, init, args.duration, model=args.model,
                          integrator=integ, friction_coefficient=args.friction,
                          progress=progress, record_steps=args.steps, stream_to=rd,
                          check_memory=not args.no_size_check, energy=energy,
                          sensors=sensors,
                          **({"keep_seconds": args.keep, "table_format": args.format}
                             if stream else {}))
    wall = time.perf_counter() - wall0
    if result.outcome == "write_failed":
        return _streamed_write_failed(result, out, rd)

    summary = result.summary()
    balance = result.energy_balance() if energy else None
    if balance is not None:
        summary["energy_balance"] = balance.as_dict()
    interrupted = result.outcome == "interrupted"
    info |= {"scoutsim_version": result.provenance.get("scoutsim_version"),
             "t_end": result.t_end}
    try:
        with _ctrl_c_deferred() as deferred:
            rd = _write_outputs(args, out, result, summary, rd, command, info, interrupted)
    except OSError as exc:        # a full disk, a directory where a file goes, permissions
        print(f"scoutsim run: error: could not write the run's files to {out}/: "
              f"{exc.strerror or exc}" + (f" ({name})" if (name := exc.filename2 or exc.filename)
                                          else ""),
              file=sys.stderr)
        if not stream:
            print(_rescue(result), file=sys.stderr)
        return EXIT_WRITE_FAILED
    files = [out / name for name in rd.files] + [out / MANIFEST]

    if args.json:
        print(dumps(summary))
    else:
        print(format_summary(summary, duration=args.duration, wall_s=wall, t_end=result.t_end,
                             friction=args.friction, load_s=load_s,
                             command_wall_s=command_wall_time()))
        if args.model == "passive" and result.outcome == "fell" \
                and max(robot.per_leg("leg_mass")) > 0:
            print("  (passive model: no actuators, so legs with mass swing freely at the hips "
                  "and the robot folds; massless legs, leg_mass = leg_inertia = 0, bound "
                  "passively: see scoutsim orbit --passive)")
        if balance is not None:
            print(format_energy(summary))
        if balance is not None and args.energy:
            cot = balance.cost_of_transport
            print(f"\nwork-energy balance over {balance.duration_s:g} s "
                  f"(mean input {balance.mean_input_power_W:.1f} W, hip work "
                  f"{balance.hip_work_J:.1f} J"
                  + (f", cost of transport {cot:.2f}" if cot is not None else "") + "):")
            print(balance.table())
        if stream and result.provenance["stream"]["kept_from_s"] is not None:
            kept = result.provenance["stream"]["kept_from_s"]
            print(f"  (streamed run: the summary covers t = {kept:.6g} - {result.t_end:.6g} s, "
                  "the tables hold the whole run)")
        print(f"wrote {', '.join(f.name for f in files)} to {out}/")
    if result.outcome == "numerical_failure":
        # what stopped the run and what to check: the parameters far from the Scout II
        # defaults, or the integrator tolerance (SimulationResult.failure)
        print(f"scoutsim run: the integration failed numerically: "
              f"{result.failure.message(cli=True)} (see summary.json and the timeseries "
              "table)", file=sys.stderr)
        return 1
    if result.outcome == "interrupted" or deferred.asked:
        return 130
    return 0
