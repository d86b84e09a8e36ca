"""The entry point: :func:`simulate` runs the hybrid model under a controller.

    result = scoutsim.simulate(robot, controller, initial_state, duration, model="II")

Parts are swappable: robot parameters (:class:`~scoutsim.parameters.RobotParameters`), the
transmission variant (``model``: "ideal", "I", "II", "passive"), the controller (the
compiled Table I law, or any object with ``command(t, sensors)``), the initial state and
the integrator settings (:class:`IntegratorSettings`).

The parts it composes have their own modules: :mod:`scoutsim.simulation.integrator` (the settings),
:mod:`scoutsim.simulation.initial_conditions` (the start as the loop takes it), :mod:`scoutsim.simulation.engine` (the
engine that runs the compiled loop in chunks), :mod:`scoutsim.simulation.budgets` (memory, disk and
wall time checked before a run) and :mod:`scoutsim.simulation.assembly` (the run put together,
as every caller of the engine does); the names other code uses are re-exported here.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
import warnings
from dataclasses import asdict, dataclass, fields

from .._core.model import layout as L
from .._version import __version__
from ..control.dispatch import plan_controller
from ..control.protocol import ControllerError, failure_message
from ..control.sensors import SensorParameters, Sensors
from ..control.startup import StartupParameters, run_startup
from ..io.run_directory import RunDirectory
from ..parameters import Environment, RobotParameters, validate_parameters, validate_robot
from ..result.simulation_result import SimulationResult
from ..state import HybridState, InitialState

# the parts simulate() composes, re-exported here as the public API of a run
from .assembly import DEFAULT_PITCH_LIMIT_DEG, PlantOptions, assemble
from .budgets import (
    STREAM_CHUNK_SECONDS,
    check_run_memory,
    check_stream_disk,
    expected_wall_time,
    physical_memory_bytes,
)
from .engine import HybridEngine, start_controller, start_engine
from .initial_conditions import default_initial_state, named_start
from .integrator import IntegratorSettings
from .record_rate import RecordedPieces, samples_per_record

__all__ = [
    "simulate",
    "Recording",
    "PLANT_OPTIONS",
    "IntegratorSettings",
    "HybridEngine",
    "ControllerError",
    "Sensors",
    "default_initial_state",
    "warm_up",
    "start_engine",
    "check_run_memory",
    "check_stream_disk",
    "expected_wall_time",
    "physical_memory_bytes",
]


def warm_up() -> float:
    """Make the compiled core ready in this process: load it from Numba's cache, compiling
    it first if it is not there (minutes on a first run; :func:`scoutsim._numba.jit.core_is_compiled`
    tells which). Every later :func:`simulate` then runs at full speed from its first call.
    Returns the wall time it took [s]."""
    t0 = time.perf_counter()
    simulate(duration=1e-3)
    return time.perf_counter() - t0


@dataclass(frozen=True)
class Recording:
    """What :func:`simulate` records and how it runs (each field is also a keyword of
    :func:`simulate`, which, given and not None, overrides the bundle's): ``progress``,
    ``chunk_seconds`` [s],
    ``record_steps``, ``check_memory``, ``stream_to``, ``keep_seconds`` [s],
    ``table_format``, ``energy``, ``record_rate`` [Hz] (see :func:`simulate`)."""

    progress: bool = False
    chunk_seconds: float = 1.0
    record_steps: bool = False
    check_memory: bool = True
    stream_to: str | os.PathLike | RunDirectory | None = None
    keep_seconds: float | None = None
    table_format: str | None = None
    energy: bool = False
    record_rate: float | None = None


#: :func:`simulate`'s keywords for the plant beyond the robot, with their defaults (those of
#: :class:`~scoutsim.simulation.assembly.PlantOptions`)
PLANT_OPTIONS = {f.name: f.default for f in dataclasses.fields(PlantOptions) if f.name != "bench"}


_DEFAULT_RECORDING = Recording()


def _recording(recording: Recording | None, given: dict) -> Recording:
    """The run's :class:`Recording`: the bundle (default ``Recording()``) with the
    recording keywords of :func:`simulate` that were given (not None) applied."""
    changes = {k: v for k, v in given.items() if v is not None}
    if recording is None and not changes:
        return _DEFAULT_RECORDING
    return dataclasses.replace(recording or _DEFAULT_RECORDING, **changes)


def _fields_dict(obj) -> dict:
    """``dataclasses.asdict(obj)`` for a parameter set of plain values (numbers, strings,
    None, tuples of numbers), without its deep copies (a tenth of a millisecond per run
    for a robot); a set holding anything else goes through ``asdict``."""
    out = {f.name: getattr(obj, f.name) for f in fields(obj)}
    for v in out.values():
        if not (
            v is None
            or isinstance(v, (int, float, str))
            or (isinstance(v, tuple) and all(isinstance(x, (int, float)) for x in v))
        ):
            return asdict(obj)
    return out


def simulate(
    robot: RobotParameters | None = None,
    controller: object | None = None,
    initial_state: InitialState | HybridState | str | None = None,
    duration: float = 10.0,
    *,
    model: str = "II",
    environment: Environment | None = None,
    integrator: IntegratorSettings | None = None,
    sensors: SensorParameters | None = None,
    startup: StartupParameters | None = None,
    friction_coefficient: float | None = None,
    pitch_limit_deg: float = DEFAULT_PITCH_LIMIT_DEG,
    passive_touchdown_angles: tuple[float, float] = (0.0, 0.0),
    passive_touchdown_world: bool = True,
    recording: Recording | None = None,
    progress: bool | None = None,
    chunk_seconds: float | None = None,
    record_steps: bool | None = None,
    check_memory: bool | None = None,
    stream_to: str | os.PathLike | RunDirectory | None = None,
    keep_seconds: float | None = None,
    table_format: str | None = None,
    energy: bool | None = None,
    record_rate: float | None = None,
) -> SimulationResult:
    """Simulate the planar Scout II model.

    Parameters
    ----------
    robot : RobotParameters, optional
        Physical parameters (default: Scout II, ``scoutsim/data/scout2.toml``).
    controller : ControllerParameters, BoundingController, CompiledController, user object or None
        Anything that follows the controller protocol (:mod:`scoutsim.control.protocol`:
        ``control_period``, ``reset(robot, sensors)``, ``command(t, sensors)``).
        ControllerParameters or a BoundingController run the compiled Table I bounding
        law; a :class:`~scoutsim.control.compiled.CompiledController` runs compiled in the
        loop; any other object's ``command`` is called from the loop at every sample
        (:mod:`scoutsim.control.dispatch`). If it raises, or returns anything but two
        finite hip torques, the run stops at that sample with a :class:`ControllerError`.
        ``None`` means the Table I defaults, except for ``model="passive"`` (no control).
    initial_state : InitialState, HybridState, "flight" or "standing", optional
        Start state (default: :func:`default_initial_state`, also named "flight"); a
        :class:`HybridState` (e.g. ``result.hybrid_state(k)``) resumes a run at one of its
        samples, to the integration tolerance (see :class:`~scoutsim.state.HybridState`).
        "standing": the robot at rest on its four legs
        (:func:`~scoutsim.state.standing_state`), set going by the start-up of
        :mod:`scoutsim.control.startup` (a step of the back legs, then a push of all
        four) and then bounding under the Table I controller, in the same run; the
        built-in controller only (``result.provenance["startup"]``, the summary's
        ``startup_duration_s``).
    duration : float
        Simulated time [s].
    model : {"II", "I", "ideal", "passive"}
        Actuation / transmission variant (docs/specification.md sections 4-5).
    environment : Environment, optional
        The floor (:class:`~scoutsim.parameters.Environment`); default ``Environment()``:
        Coulomb mu = :data:`~scoutsim.parameters.DEFAULT_FRICTION_COEFFICIENT` (1.0), no
        slip for massless legs (their ground force lies along the leg).
    integrator : IntegratorSettings, optional
        Tolerances of the reference integrator.
    friction_coefficient : float or None
        Shortcut for ``environment=Environment(friction_coefficient=...)``: Coulomb
        coefficient of the toe, ``inf`` = no slip (not together with ``environment``);
        None (default): the environment's.
    pitch_limit_deg : float
        |pitch| [deg] that counts as a fall, in (0, 90) (default 60;
        docs/specification.md section 3).
    passive_touchdown_angles : (back, front) [rad]
        Massless-leg configuration only: where the legs are placed in flight (default
        (0, 0)).
    passive_touchdown_world : bool
        Massless-leg configuration only: angles from the world vertical (True, default) or
        relative to the torso (False).
    sensors : SensorParameters, optional
        How the robot's sensors measure (:class:`~scoutsim.control.sensors.SensorParameters`:
        noise, bias, resolution and delay per channel, seeded; a robot file's
        ``[sensors]``: :func:`~scoutsim.control.sensors.load_sensors`); default: ideal
        sensors. Every controller, the built-in one too, sees the sensors' readings.
    startup : StartupParameters, optional
        With ``initial_state="standing"`` only: the start-up's parameters (default
        ``StartupParameters()``).
    recording : Recording, optional
        The recording keywords below (``progress`` ... ``energy``) as one bundle (default
        ``Recording()``); a keyword given as well (not None) overrides its field. Each
        keyword's None means "not given": the bundle's field, whose default is the one
        named below.
    progress : bool or None
        Show a progress bar (tqdm) on stderr (default False).
    chunk_seconds : float or None
        Simulated time [s] per call of the compiled loop (progress updates, interrupts;
        default 1 s; a streamed or thinned run takes at least
        :data:`~scoutsim.simulation.budgets.STREAM_CHUNK_SECONDS` per call); the result
        does not depend on it.
    record_steps : bool or None
        Also record every integrator step (``result.steps``: time, state and plant modes at
        the end of each step, layout ``STP_*``); off by default (a 10 s Model II run takes
        about 13 000 steps).
    check_memory : bool or None
        Refuse (ValueError) a run whose time series would not fit in this machine's memory
        (:func:`~scoutsim.simulation.budgets.check_run_memory`) before allocating anything
        (default True); False to try anyway. A streamed run is checked against the free
        disk space instead (:func:`~scoutsim.simulation.budgets.check_stream_disk`).
    stream_to : directory (a path, or a :class:`~scoutsim.io.run_directory.RunDirectory`) or None
        Stream the run to this directory as it is computed (:mod:`scoutsim.simulation.streaming`):
        the ``timeseries``, ``events`` (and ``steps``) tables and a manifest, written chunk
        by chunk, so the memory a run needs does not grow with its duration. The returned
        result then holds only the last ``keep_seconds`` of the run (outcome, end time and
        statistics are the whole run's); ``SimulationResult.load(stream_to)`` reads all.
        Default None: the run is kept in memory.
    keep_seconds : float or None
        With ``stream_to``: seconds at the end of the run kept in memory and returned
        (default :data:`scoutsim.simulation.streaming.DEFAULT_KEEP_SECONDS`, 60 s).
    table_format : {"parquet", "csv"} or None
        With ``stream_to``: the tables' format (default Parquet if pyarrow is installed).
    record_rate : float or None
        Samples per second [Hz] of the recorded time series (``result.t``, ``state``,
        ``aux``, ``modes``, ``energy_series`` and a streamed run's ``timeseries``
        table): the control rate divided by a whole number k (1000, 500, 250, 200, 100,
        ... Hz for the 1 ms control period); every k-th control sample from the first is
        kept, and the run's last. Default None: every control sample. The events (times
        and exact states), the integrator steps, the energy totals
        (``result.energy_flows``, ``energy_balance()``), the strides, gait metrics and
        per-stride energies are those of the full-rate run, bit for bit: the strides are
        read from every sample as the run is computed
        (:mod:`scoutsim.simulation.record_rate`). Sample-based figures of the summary
        (the saturation fractions, the largest belt deflection) and plots read the kept
        samples. The simulation costs the same; memory and tables shrink by k.
    energy : bool or None
        Account for every power flow of the model over the whole run (electrical energy,
        copper and transmission losses, hip work, joint, belt, leg and toe friction and
        damping, constraint work; docs/model.md "Work-energy balance"), integrated on every
        integrator step: ``result.energy_flows``, ``result.energy_balance()`` (default
        off). The motion is the same bit for bit; the run takes a little longer (the power
        at every stage of every step, read from the step's own evaluations: 10 s of
        Model II or Model I 1.11x).

    Returns
    -------
    SimulationResult
        Time series at the control samples, events, outcome and provenance. A run that
        falls or fails numerically returns normally with ``outcome`` saying so and the data
        up to that point; a KeyboardInterrupt also returns the data computed so far
        (``outcome = "interrupted"``; a streamed run writes it, marked partial). A streamed
        run whose tables the disk refuses (full) stops there with ``outcome =
        "write_failed"`` (and a RuntimeWarning): the tables keep what was written, as far
        as the disk allows (``result.provenance["stream"]``: ``write_error``,
        ``written_until_s``, ``tables_kept``), the result the run's last ``keep_seconds``.

    Raises
    ------
    ControllerError
        A controller's ``command(t, sensors)`` raised, or returned something other than two
        finite hip torques (a compiled controller: a nonzero status). The message names the controller, the sample time and
        what it raised or returned; the error's ``result`` holds the run up to the sample
        before, with ``outcome = "controller_error"`` (a streamed run's tables hold it
        too, marked partial).
    """
    rec = _recording(
        recording,
        dict(
            progress=progress,
            chunk_seconds=chunk_seconds,
            record_steps=record_steps,
            check_memory=check_memory,
            stream_to=stream_to,
            keep_seconds=keep_seconds,
            table_format=table_format,
            energy=energy,
            record_rate=record_rate,
        ),
    )
    progress, chunk_seconds, record_steps, check_memory = (
        rec.progress,
        rec.chunk_seconds,
        rec.record_steps,
        rec.check_memory,
    )
    stream_to, keep_seconds, table_format, energy, record_rate = (
        rec.stream_to,
        rec.keep_seconds,
        rec.table_format,
        rec.energy,
        rec.record_rate,
    )
    robot = validate_robot(robot if robot is not None else RobotParameters())
    if environment is not None and friction_coefficient is not None:
        raise ValueError(
            "friction_coefficient and environment are not allowed together: "
            "give the floor's friction in environment=Environment(...)"
        )
    if environment is None:
        environment = Environment(friction_coefficient=friction_coefficient)
    friction_coefficient = environment.friction_for(robot)
    if not (isinstance(duration, (int, float)) and math.isfinite(duration) and duration > 0):
        raise ValueError(f"duration = {duration!r} s is not allowed: must be a finite number > 0")
    plant = PlantOptions(
        friction_coefficient=friction_coefficient,
        pitch_limit_deg=pitch_limit_deg,
        passive_touchdown_angles=passive_touchdown_angles,
        passive_touchdown_world=passive_touchdown_world,
    )
    if stream_to is None and (keep_seconds is not None or table_format is not None):
        raise ValueError("keep_seconds and table_format are only allowed with stream_to")
    plan = plan_controller(controller, model, robot, sensors)
    cparams = plan.parameters
    if plan.kind == "builtin":
        validate_parameters(robot, cparams)
    dt = plan.control_period
    every = samples_per_record(record_rate, dt)
    if check_memory and stream_to is None:
        check_run_memory(duration, record_steps=record_steps, dt=dt, record_every=every)
    initial_state, startup = named_start(
        initial_state, startup, model, robot, cparams, plan.controller
    )
    init = initial_state or default_initial_state(model, robot, passive_touchdown_angles)
    resume = isinstance(init, HybridState)
    if not isinstance(init, (HybridState, InitialState)):
        raise TypeError(
            "initial_state must be an InitialState, a HybridState, 'flight' "
            f"or 'standing', not {type(init).__name__}"
        )
    setup = assemble(robot, model, init, plan, plant=plant, integrator=integrator)
    integ = setup.integrator
    chunk = max(1, int(round(chunk_seconds / dt)))
    stream = None
    if stream_to is not None:
        from .streaming import DEFAULT_KEEP_SECONDS, RunStream

        stream = RunStream(
            stream_to,
            fmt=table_format,
            keep_seconds=(DEFAULT_KEEP_SECONDS if keep_seconds is None else keep_seconds),
        )
        if check_memory:
            check_stream_disk(duration, stream.dir, record_steps=record_steps, dt=dt)
    # the pieces of a thinned or streamed run, its strides read from every sample
    sink = RecordedPieces(every, stream, robot) if every > 1 or stream is not None else None
    if sink is not None:
        # fewer, larger pieces: each costs ~1 ms of stride record and ~5 ms of table writing
        chunk = max(chunk, int(round(STREAM_CHUNK_SECONDS / dt)))
    eng = HybridEngine.assembled(
        setup,
        duration,
        record_steps=record_steps,
        rows=None if sink is None else chunk + 2,
        energy=energy,
    )
    user_ctrl = plan.controller
    bridge = start_controller(eng, plan, robot, init)
    wall0 = time.perf_counter()
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(
            total=round(duration, 3),
            unit="s",
            unit_scale=False,
            desc=f"Model {model}",
            leave=False,
            bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} s [{elapsed}<{remaining}]",
        )
    interrupted = False
    started = None  # the start-up from standing: its StartupRecord
    written = True  # a streamed run's tables took every piece so far
    try:
        if startup is not None:
            assert cparams is not None, "a start-up hands over to the built-in controller"
            started = run_startup(eng, startup, cparams)
            if bar is not None:
                bar.update(round(eng.k * dt, 6))
            written = sink is None or sink.take(eng)
        while written and eng.running:
            k_prev = eng.k
            eng.advance(eng.k + chunk)
            if bridge is not None and bridge.interrupted:
                raise KeyboardInterrupt
            if sink is not None and not sink.take(eng):
                break  # the disk refused a piece (full): outcome "write_failed", below
            if bar is not None:
                bar.update(round((eng.k - k_prev) * dt, 6))
    except KeyboardInterrupt:
        interrupted = True
    except BaseException:
        if stream is not None:
            stream.abort()
        raise
    finally:
        if bar is not None:
            bar.close()
    wall = time.perf_counter() - wall0
    provenance = {
        "scoutsim_version": __version__,
        "model": model,
        "hip_unit": setup.hip_unit,
        "robot": _fields_dict(robot),
        "controller": (_fields_dict(cparams) if cparams is not None else None),
        "controller_kind": plan.label,
        "initial_state": _fields_dict(init)
        | (
            {"kind": "standing"}
            if startup is not None
            else {"kind": "hybrid_state"}
            if resume
            else {}
        ),
        "integrator": _fields_dict(integ),
        "duration_s": duration,
        "friction_coefficient": (
            None if math.isinf(friction_coefficient) else friction_coefficient
        ),
        "pitch_limit_deg": pitch_limit_deg,
        "passive_touchdown_angles_rad": list(passive_touchdown_angles),
        "passive_touchdown_world": passive_touchdown_world,
        "control_period_s": dt,
    }
    if startup is not None:
        assert cparams is not None, "a start-up hands over to the built-in controller"
        provenance["startup"] = (
            started.to_dict()
            if started is not None
            else {"parameters": asdict(startup.resolved(cparams))}
        )
    if sensors is not None and not sensors.is_ideal():
        provenance["sensors"] = sensors.as_dict()
    error: ControllerError | None = None
    failure: tuple | None = None  # (sample, returned, exception) of a controller's failure
    if eng.status == L.ST_CONTROLLER_ERROR and not interrupted:
        status = 0
        if bridge is not None and bridge.failure is not None:
            failure = bridge.failure
        else:  # a compiled controller: its status, or the torques it wrote
            failure = (eng.k, tuple(float(v) for v in eng.cmd), None)
            status = int(plan.block.ints[L.CB_STATUS])
        k_fail, returned, exc = failure
        message = failure_message(user_ctrl, k_fail, dt, returned, exc, status)
        provenance["controller_error"] = message
        error = ControllerError(
            message, controller=user_ctrl, t=k_fail * dt, sample=k_fail, returned=returned
        )
    if every > 1:
        provenance["record_rate_hz"] = 1.0 / (every * dt)
    if stream is None:
        if sink is None:
            result = eng.result(provenance, interrupted, {"wall_time_s": wall})
        else:
            sink.take(eng)  # (a Ctrl-C between the compiled call and take(): its rows)
            sink.close()
            result = sink.result(
                eng.result(
                    provenance,
                    interrupted,
                    {"wall_time_s": wall},
                    last_sample_t=sink.last_sample_t,
                )
            )
        if error is not None:
            error.result = result
            raise error from (failure[2] if failure is not None else None)
        return result
    assert sink is not None, "a streamed run takes its pieces through the sink"
    try:
        if stream.write_error is None:
            if sink.take(eng):  # a Ctrl-C between the compiled call and take(): its rows
                sink.close()
    except BaseException:
        stream.abort()
        raise
    whole = eng.result(
        provenance, interrupted, {"wall_time_s": wall}, last_sample_t=sink.last_sample_t
    )
    if stream.write_error is not None:
        whole.outcome = "write_failed"
        warnings.warn(
            f"simulate: the streamed run's tables could not be written to "
            f"{stream.dir} ({stream.write_error}); the run stopped at t = "
            f"{whole.t_end:g} s: the result holds its last "
            f"{stream.keep_seconds:g} s, result.provenance['stream'] says what the "
            "tables kept",
            RuntimeWarning,
            stacklevel=2,
        )
    kept = stream.finish(
        whole, partial=interrupted or stream.write_error is not None or error is not None
    )
    kept.stride_record = sink.stride_record()
    if error is not None:
        error.result = kept
        raise error from (failure[2] if failure is not None else None)
    return kept
