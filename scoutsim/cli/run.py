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
(or result.npz) back bit for bit. ``--record-rate HZ`` thins the timeseries table to HZ
samples per second; the summary's strides, gait metrics and energy stay the full-rate
run's. A run that would take more than ``--memory-budget`` (1 GB) held in memory streams
its tables to disk as they are computed (``--stream``).

Exit code 1 if the integration failed numerically, 130 if interrupted (the data so far is
still written); a fall is a completed run (exit 0, the summary says so).

Here are the command's options and the run; the printed summary is in
:mod:`scoutsim.cli.run_summary`, the files beyond the run's tables and the rescue of a run
whose directory could not be written in :mod:`scoutsim.cli.run_outputs`.
"""

from __future__ import annotations

import math
import sys
import time

from ..io.run_directory import MANIFEST, RunDirectory
from ..result.columns import COLUMN_UNITS, column_unit  # noqa: F401 (re-exported by scoutsim.cli)
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
from .run_outputs import (
    EXIT_WRITE_FAILED,
    ctrl_c_deferred,
    rescue,
    streamed_write_failed,
    write_timeseries_csv,
)
from .run_summary import format_energy, format_summary

#: memory [GB] a run's time series may take before ``scoutsim run`` streams it to disk
DEFAULT_MEMORY_BUDGET_GB = 1.0


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
        NAME,
        parents=[common],
        help="simulate one run, print a summary, write its tables",
        description="Simulate one bounding run, print a summary table (what the robot "
        "did, the gait, the simulation's real-time factor and the whole command's "
        "wall time) and write to DIR: timeseries and events tables "
        "(Parquet, or gzip-compressed CSV without pyarrow) and summary.json; "
        "figures with --plots. SimulationResult.load(DIR) reads the run back.",
    )
    run.add_argument(
        "--model", choices=MODELS, default="II", help="actuator/transmission model (default: II)"
    )
    run.add_argument(
        "--start",
        choices=("flight", "standing"),
        default="flight",
        help="flight (default): released in flight at --speed, --height, "
        "--pitch-rate; standing: at rest on its four legs, set going by "
        "the start-up (a step of the back legs, then a push of all four) "
        "into the Table I bound "
        "(summary: startup_duration_s)",
    )
    add_duration_option(run, DEFAULT_DURATION_S)
    add_controller_option(run)
    run.add_argument(
        "--speed",
        type=finite_float,
        default=None,
        metavar="V",
        help=f"initial forward speed [m/s] (default: {_DEFAULT_START.dx:g}; "
        "passive model: scoutsim.default_initial_state)",
    )
    run.add_argument(
        "--height",
        type=positive_float,
        default=None,
        metavar="Y",
        help=f"initial torso COM height [m] (default: {_DEFAULT_START.y:g}; "
        "passive model: higher, so that its hanging legs clear the ground "
        "by the same margin)",
    )
    run.add_argument(
        "--pitch-rate",
        type=finite_float,
        default=None,
        metavar="W",
        help=f"initial pitch rate [deg/s] (default: {math.degrees(_DEFAULT_START.dtheta):g})",
    )
    run.add_argument(
        "--steps",
        action="store_true",
        help="also record every integrator step (steps table: time, state, plant modes)",
    )
    run.add_argument(
        "--format",
        choices=FORMATS,
        default=None,
        help="format of the tables: parquet (default when pyarrow is "
        "installed) or csv (gzip-compressed, the default otherwise)",
    )
    add_plots_option(
        run,
        False,
        "run.png (pitch, height, leg angles and states, hip "
        "torques; runs over 4 s: an overview and the last strides), "
        "torque_speed.png (paper Fig. 11) and, with the energy "
        "accounting, stride_power.png (power over the last steady "
        "stride by destination)",
    )
    run.add_argument(
        "--csv",
        action="store_true",
        help="also write timeseries.csv (plain CSV, one row per sample)",
    )
    run.add_argument(
        "--npz",
        action="store_true",
        help="also write result.npz (the whole result in one NumPy file)",
    )
    run.add_argument(
        "--stream",
        action="store_true",
        help="write the tables as the run is computed, keeping only its last "
        "--keep seconds in memory (for long runs: the strides, gait "
        "metrics and energy in the summary cover the whole run, the "
        "figures the kept end). Chosen by itself when the time series "
        "would take more than --memory-budget; refused before starting "
        "when the disk cannot hold the tables",
    )
    run.add_argument(
        "--keep",
        type=positive_float,
        default=None,
        metavar="S",
        help="with --stream: seconds at the end of the run kept in memory for "
        f"the summary and figures (default: {DEFAULT_KEEP_SECONDS:g})",
    )
    run.add_argument(
        "--record-rate",
        type=positive_float,
        default=None,
        metavar="HZ",
        help="samples per second of the timeseries table: the control rate "
        "(1000 Hz) divided by a whole number, e.g. 100 (default: every control "
        "sample). The events, strides, gait metrics and energy balance stay "
        "those of the full-rate run; the table and memory shrink",
    )
    run.add_argument(
        "--memory-budget",
        type=positive_float,
        default=DEFAULT_MEMORY_BUDGET_GB,
        metavar="GB",
        help="memory the run may take; a run that would take more held in "
        "memory (about 4x its time series) streams its tables to disk as they "
        "are computed, as with --stream (default: "
        f"{DEFAULT_MEMORY_BUDGET_GB:g})",
    )
    run.add_argument(
        "--no-size-check",
        action="store_true",
        help="skip the checks of the memory and disk space the run needs (and "
        "do not stream because of them)",
    )
    run.add_argument(
        "--energy",
        action="store_true",
        help="also print the whole work-energy balance table (every term, the residual)",
    )
    run.add_argument(
        "--no-energy",
        action="store_true",
        help="no energy accounting, for a faster run (by default every "
        "power flow is integrated: electrical energy, copper and "
        "transmission losses, friction, dampers, impacts, cost of "
        "transport in summary.json and the energy block; it leaves the "
        "motion the same and makes the simulation of 10 s of Model II "
        "1.11x slower)",
    )
    run.add_argument(
        "--json",
        action="store_true",
        help="print the summary as JSON on stdout instead of the table",
    )
    run.set_defaults(func=execute)


def _write_outputs(args, out, result, summary, rd, command, info, interrupted):
    """Write the run's files into ``out`` (``rd``: the streamed run's directory, whose
    tables are written already, or None); the finished RunDirectory."""
    if rd is None:
        rd = RunDirectory(out, command=command, info=info).open()
        for path in result.save_tables(out, fmt=args.format):
            rd.add(path.name)
    else:
        rd.info = info  # (the streamed tables are already written and listed)
    rd.write("summary.json", lambda p: write_json(p, summary))
    if args.csv:
        rd.write("timeseries.csv", lambda p: write_timeseries_csv(result, p))
    if args.npz:
        rd.write("result.npz", lambda p: result.save(p))
    if args.plots:
        from ..presentation.plots import plot_run, plot_torque_speed

        rd.write("run.png", lambda p: plot_run(result, p, overview="auto"))
        rd.write("torque_speed.png", lambda p: plot_torque_speed(result, "both", p))
        if (
            result.energy_series is not None
            and result.provenance.get("model") != "passive"
            and any(s.energy_t_start is not None for s in result.strides)
        ):
            from ..presentation.plots import plot_stride_power

            rd.write("stride_power.png", lambda p: plot_stride_power(result, p))
    rd.finish(outcome=result.outcome, partial=interrupted)
    return rd


def _stream_choice(args, control_period: float) -> bool:
    """Whether the run streams its tables to disk: asked with --stream, or chosen because
    its time series would take more than --memory-budget (said on stderr)."""
    from ..simulation.budgets import PEAK_PER_SERIES, time_series_bytes
    from ..simulation.record_rate import samples_per_record

    if args.keep is not None and not args.stream:
        raise UsageError("--keep is only allowed with --stream")
    try:
        every = samples_per_record(args.record_rate, control_period)
    except ValueError as exc:
        raise UsageError(str(exc).replace("record_rate", "--record-rate", 1)) from None
    need = time_series_bytes(
        args.duration, record_steps=args.steps, dt=control_period, record_every=every
    )
    fits = args.no_size_check or need * PEAK_PER_SERIES <= args.memory_budget * 1e9
    stream = args.stream or not fits
    if stream and not args.stream and (args.csv or args.npz):
        raise UsageError(
            f"{'--csv' if args.csv else '--npz'} needs the whole time series in memory, "
            f"and {args.duration:g} s held in memory would take about "
            f"{need * PEAK_PER_SERIES / 1e9:.2g} GB, more than the memory budget of "
            f"{args.memory_budget:g} GB: give a larger --memory-budget, a lower "
            "--record-rate, or leave it out"
        )
    if stream and (args.csv or args.npz):
        raise UsageError(
            f"{'--csv' if args.csv else '--npz'} is not allowed with a streamed "
            "run (it needs the whole time series in memory): read the streamed "
            "tables instead (SimulationResult.load(DIR))"
        )
    if stream and not args.stream:
        print(
            f"scoutsim run: {args.duration:g} s held in memory would take about "
            f"{need * PEAK_PER_SERIES / 1e9:.2g} GB, "
            f"more than the memory budget of {args.memory_budget:g} GB: streaming the "
            "tables to disk as they are computed (the strides, gait metrics and "
            "energy cover the whole run, the figures its last "
            f"{DEFAULT_KEEP_SECONDS:g} s; see --stream, --keep, --memory-budget, "
            "--record-rate)",
            file=sys.stderr,
        )
    return stream


def execute(args) -> int:
    from ..simulation.initial_conditions import default_initial_state
    from ..simulation.simulator import simulate, warm_up

    robot, cparams = load_parameters(args.robot)
    sensors = load_sensors(args.robot, robot)
    law, cparams = controller_choice(args.controller, cparams)
    if args.controller != "table-i" and args.model == "passive":
        raise UsageError(
            f"--controller {args.controller} is not allowed with --model "
            "passive (the passive model has no controller)"
        )
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
            raise UsageError(
                "--speed, --height and --pitch-rate are only allowed with "
                "--start flight (a standing robot is at rest)"
            )
        if args.model == "passive":
            raise UsageError(
                "--start standing is not allowed with --model passive (no "
                "actuator holds or sets going the standing robot)"
            )
        if not isinstance(controller, type(cparams)):
            raise UsageError(
                f"--start standing is not allowed with --controller "
                f"{args.controller}: the start-up hands over to the Table I "
                "controller"
            )
        init = "standing"
    out = out_dir(args.out)
    progress = show_progress(args)

    if args.energy and args.no_energy:
        raise UsageError("--energy and --no-energy are not allowed together")
    energy = not args.no_energy
    check_expected_time(args, {args.model: args.duration})
    stream = _stream_choice(args, float(getattr(controller, "control_period", 1e-3)))
    load_s = warm_up()
    command = " ".join(["scoutsim"] + sys.argv[1:])
    info = {
        "model": args.model,
        "controller": args.controller,
        "duration_s": args.duration,
        "streamed": stream,
    }
    # a streamed run's directory is entered when its first rows arrive (streaming.RunStream)
    rd = RunDirectory(out, command=command, info=info) if stream else None
    wall0 = time.perf_counter()
    with usage_errors():  # invalid initial state or option
        result = simulate(
            robot,
            controller,
            init,
            args.duration,
            model=args.model,
            integrator=integ,
            friction_coefficient=args.friction,
            progress=progress,
            record_steps=args.steps,
            stream_to=rd,
            check_memory=not args.no_size_check,
            energy=energy,
            sensors=sensors,
            record_rate=args.record_rate,
            **({"keep_seconds": args.keep, "table_format": args.format} if stream else {}),
        )
    wall = time.perf_counter() - wall0
    if result.outcome == "write_failed":
        return streamed_write_failed(result, out, rd)

    summary = result.summary()
    balance = result.energy_balance() if energy else None
    if balance is not None:
        summary["energy_balance"] = balance.as_dict()
    interrupted = result.outcome == "interrupted"
    info |= {"scoutsim_version": result.provenance.get("scoutsim_version"), "t_end": result.t_end}
    try:
        with ctrl_c_deferred() as deferred:
            rd = _write_outputs(args, out, result, summary, rd, command, info, interrupted)
    except OSError as exc:  # a full disk, a directory where a file goes, permissions
        print(
            f"scoutsim run: error: could not write the run's files to {out}/: "
            f"{exc.strerror or exc}"
            + (f" ({name})" if (name := exc.filename2 or exc.filename) else ""),
            file=sys.stderr,
        )
        if not stream:
            print(rescue(result), file=sys.stderr)
        return EXIT_WRITE_FAILED
    files = [out / name for name in rd.files] + [out / MANIFEST]

    if args.json:
        print(dumps(summary))
    else:
        print(
            format_summary(
                summary,
                duration=args.duration,
                wall_s=wall,
                t_end=result.t_end,
                friction=args.friction,
                load_s=load_s,
                command_wall_s=command_wall_time(),
            )
        )
        if (
            args.model == "passive"
            and result.outcome == "fell"
            and max(robot.per_leg("leg_mass")) > 0
        ):
            print(
                "  (passive model: no actuators, so legs with mass swing freely at the hips "
                "and the robot folds; massless legs, leg_mass = leg_inertia = 0, bound "
                "passively: see scoutsim orbit --passive)"
            )
        if balance is not None:
            print(format_energy(summary))
        if balance is not None and args.energy:
            cot = balance.cost_of_transport
            print(
                f"\nwork-energy balance over {balance.duration_s:g} s "
                f"(mean input {balance.mean_input_power_W:.1f} W, hip work "
                f"{balance.hip_work_J:.1f} J"
                + (f", cost of transport {cot:.2f}" if cot is not None else "")
                + "):"
            )
            print(balance.table())
        if stream and result.provenance["stream"]["kept_from_s"] is not None:
            kept = result.provenance["stream"]["kept_from_s"]
            print(
                f"  (streamed run: the strides, gait metrics and energy cover the whole "
                f"run, the figures and the sample-based figures t = {kept:.6g} - "
                f"{result.t_end:.6g} s; the tables hold the whole run)"
            )
        print(f"wrote {', '.join(f.name for f in files)} to {out}/")
    if result.outcome == "numerical_failure":
        # what stopped the run and what to check: the parameters far from the Scout II
        # defaults, or the integrator tolerance (SimulationResult.failure)
        print(
            f"scoutsim run: the integration failed numerically: "
            f"{result.failure.message(cli=True)} (see summary.json and the timeseries "
            "table)",
            file=sys.stderr,
        )
        return 1
    if result.outcome == "interrupted" or deferred.asked:
        return 130
    return 0
