"""The engine of a run: :class:`HybridEngine` drives the compiled hybrid model
(:func:`scoutsim._core.loop.run`) in chunks of control samples and turns its buffers into a
result; :func:`start_engine` puts one together for a caller that drives it itself."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from .._core.loop import Carry, Control, Records, Span, effective_method, readings_at, run_entry
from .._core.model import layout as L
from .._core.model.evaluate import NSTIFF
from .._core.model.flags import flag_is_set
from .._core.model.rigid_body import state_energy
from .._core.numerics.dopri5 import eval_workspace
from .._core.numerics.hybrid import HW_EVAL_KEPT, HW_STEP, NHW, STEP_HEADROOM
from .._core.numerics.stats import NSTAT, S_HMIN, STAT_NAMES
from .._core.numerics.stepper import METHOD_AUTO
from .._core.numerics.work import Plant
from ..control.bounding import C_KDB_B, C_KDB_F, C_KPB_B, C_KPB_F, SCHEDULABLE
from ..control.dispatch import (
    PythonBridge,
    plan_controller,
    read_controller_state,
    write_controller_state,
)
from ..control.sensors import SensorParameters, Sensors
from ..parameters import RobotParameters, validate_parameters, validate_robot
from ..result.simulation_result import SimulationResult
from ..state import HybridState, InitialState
from .assembly import DEFAULT_PITCH_LIMIT_DEG, PlantOptions, RunSetup, assemble
from .budgets import EVENT_ROWS_PER_S
from .integrator import METHOD_CODES, IntegratorSettings
from .sensitivities import engine_tangent, smoothness, with_hook

__all__ = ["HybridEngine", "start_controller", "start_engine", "RETUNABLE"]

#: ControllerParameters field -> slot of the built-in Table I controller's array, for the
#: fields a caller may change while the engine runs (:meth:`HybridEngine.retune`): the
#: set-points a schedule may change (``control.bounding.SCHEDULABLE``) and the
#: stance-brake gains (the start-up from standing, :mod:`scoutsim.control.startup`)
RETUNABLE = {
    **SCHEDULABLE,
    "brake_kp_back": C_KPB_B,
    "brake_kd_back": C_KDB_B,
    "brake_kp_front": C_KPB_F,
    "brake_kd_front": C_KDB_F,
}


class HybridEngine:
    """One run of the compiled hybrid model (:func:`scoutsim._core.loop.run`): its
    time-series buffers and everything carried from one call to the next (state, modes,
    controller states, step-size guess, ARK splitting, armed events). :func:`~scoutsim.simulation.simulator.simulate` and
    the bench rigs (:mod:`scoutsim.identification.rigs`) drive it in chunks of control
    samples; cutting a run into chunks does not change it."""

    #: integrator steps the step buffer holds at first (about 6 s of a Model II run at the
    #: default tolerance: 1.3 steps per control period)
    STEP_ROWS = 8192

    def __init__(
        self,
        P,
        C,
        start,
        duration: float,
        dt: float,
        integrator: IntegratorSettings,
        record_steps: bool = False,
        rows: int | None = None,
        energy: bool = False,
        *,
        block,
    ):
        """``P``, ``C``: the packed robot and Table I parameters; ``start`` = (s, mi, mf,
        ls): the state, the modes and the leg states the run starts from (kept and
        advanced in place)."""
        s, mi, mf, ls = start
        self.P, self.C, self.s, self.mi, self.mf, self.ls = P, C, s, mi, mf, ls
        # the controller and the sensors (control/block.py, control/dispatch.py)
        self.block = block
        self.dt = dt
        self.integ = integrator
        if integrator.rtol is None or integrator.atol is None:
            raise ValueError(
                "the engine runs resolved integrator settings "
                "(IntegratorSettings.resolved: rtol and atol set)"
            )
        self.rtol, self.atol = float(integrator.rtol), float(integrator.atol)
        n_total = int(round(duration / dt)) + 1
        self.k_last = n_total - 1
        # rows: the samples one call may record when a RunStream empties the buffers after
        # each call (memory bounded); None: the whole run
        if rows is not None:
            n_total = min(n_total, rows + 1)
            duration = min(duration, rows * dt)
        self.cmd = np.zeros(2)
        # [step-size guess, ARK factors valid, evaluation workspace valid] (loop.run)
        self.hwork = np.zeros(NHW)
        self.hwork[HW_STEP] = integrator.initial_step
        self.ew = eval_workspace()
        self.sfwork = np.zeros((L.NS, 2 * NSTIFF))
        # the sensitivities the run carries (none: no columns; carry_sensitivities)
        self.tangent = engine_tangent(self, 0)
        self.out_t = np.zeros(n_total + 1)
        self.out_s = np.zeros((n_total + 1, L.NS))
        self.out_aux = np.zeros((n_total + 1, L.NAUX))
        self.out_ls = np.zeros((n_total + 1, L.NRM), dtype=np.int8)
        self.ev = np.zeros((max(1024, int(EVENT_ROWS_PER_S * duration) + 256), L.NEVBUF))
        # every integrator step if record_steps (numerics.events.record_step): room for
        # STEP_ROWS steps beyond the headroom one control period may need (np.zeros:
        # pages a run does not reach are never touched); doubled when it runs low
        self.steps = np.zeros((STEP_HEADROOM + self.STEP_ROWS if record_steps else 0, L.NSTEPREC))
        self.stepc = np.array([0, 1 if record_steps else 0], dtype=np.int64)
        # the work-energy accounting (layout EN_*; empty: off), the touchdown impacts'
        # losses [J] and the mechanical energy [J] at the first sample
        self.energy = np.zeros(L.NEN if energy else 0)
        # the accumulator at every recorded sample (rows as out_t; (0, NEN): off)
        self.out_energy = np.zeros((n_total + 1 if energy else 0, L.NEN))
        self.impact_loss = 0.0
        self.energy_start: float | None = None
        self.stats = np.zeros(NSTAT)
        self.stats[S_HMIN] = np.inf
        self.armed = np.zeros(L.NEV, dtype=np.bool_)
        self.n_out = self.nev = self.k = 0
        self.event_records_lost = 0
        self.status = L.ST_RUNNING
        self._entry: Callable | None = None  # the compiled run loop for this engine's method
        #: the integration method's code (stepper.METHOD_*, "auto" resolved)
        self._method = effective_method(
            METHOD_CODES.get(self.integ.method, METHOD_AUTO), int(self.P[L.P_HIP_UNIT])
        )
        self.t_now = 0.0
        # the controller's plan and a Python controller's bridge (start_controller)
        self.plan: Any = None
        self.bridge: Any = None

    @classmethod
    def assembled(
        cls,
        setup: RunSetup,
        duration: float,
        *,
        record_steps: bool = False,
        rows: int | None = None,
        energy: bool = False,
    ) -> HybridEngine:
        """An engine at sample 0 of the assembled run ``setup``
        (:func:`~scoutsim.simulation.assembly.assemble`), ``duration`` [s] long."""
        return cls(
            setup.P,
            setup.plan.C,
            setup.start,
            duration,
            setup.control_period,
            setup.integrator,
            record_steps,
            rows=rows,
            energy=energy,
            block=setup.plan.block,
        )

    def __getstate__(self):
        # the compiled run loop does not pickle: the next advance() looks it up again
        return self.__dict__ | {"_entry": None}

    @property
    def running(self) -> bool:
        return self.k <= self.k_last and self.status == L.ST_RUNNING

    # -- the current state by name (for a caller that drives the engine itself) -----------
    @property
    def x(self) -> float:
        """Torso COM forward position now [m]."""
        return float(self.s[L.IX])

    @property
    def height(self) -> float:
        """Torso COM height now [m]."""
        return float(self.s[L.IY])

    @property
    def pitch(self) -> float:
        """Torso pitch now [rad], nose up positive."""
        return float(self.s[L.ITH])

    @property
    def stopped(self) -> bool:
        """True once the run loop has stopped the run: it fell, failed numerically or its
        controller failed (reaching the end of the run does not count)."""
        return self.status != L.ST_RUNNING

    @property
    def fell(self) -> bool:
        """True if the run stopped because the robot fell (height or pitch limit)."""
        return self.status == L.ST_FELL

    @property
    def status_name(self) -> str:
        """The run loop's status by name: "running" until it stops the run, then "fell",
        "numerical_failure" or "controller_error"."""
        return L.STATUS_NAMES[self.status]

    def toe_position(self, leg) -> tuple[float, float]:
        """(x, y) of virtual leg ``leg``'s toe [m] (0 back, 1 front), from the model's
        evaluation at the state of the last :meth:`read_sensors` (what
        ``SimulationResult.toe_position`` records at a sample)."""
        o = int(leg) * L.NAUX_LEG
        aux = self.block.last[L.NS :]
        return float(aux[o + L.A_TOE_X]), float(aux[o + L.A_TOE_Y])

    def hybrid_state(self) -> HybridState:
        """The hybrid state now, at control sample ``k`` before the controller's command
        there: the state, every mode, the leg states, the held hip torques and (an engine
        started by :func:`start_controller`) the controller's own state. A run resumed from
        it continues this one to the integration tolerance (see
        :class:`~scoutsim.state.HybridState`)."""
        mi, mf = self.mi, self.mf
        plan = self.plan
        return HybridState(
            state=self.s.copy(),
            leg_states=tuple(int(v) for v in self.ls),
            contact_modes=(int(mi[L.MI_CONTACT_B]), int(mi[L.MI_CONTACT_B + 1])),
            motor_modes=(int(mi[L.MI_MOTOR_B]), int(mi[L.MI_MOTOR_B + 1])),
            slide_directions=(int(mi[L.MI_SLIDE_DIR_B]), int(mi[L.MI_SLIDE_DIR_B + 1])),
            toe_anchors=(float(mf[L.MF_ANCHOR_B]), float(mf[L.MF_ANCHOR_B + 1])),
            controller_state=read_controller_state(plan) if plan is not None else (),
            held_torques=(float(self.cmd[0]), float(self.cmd[1])),
        )

    def event_times(self, kind: str, leg: int, since: int = 0) -> np.ndarray:
        """Times [s] of the events of ``kind`` (a name of
        :data:`~scoutsim.names.EVENT_KIND_NAMES`: "liftoff", "touchdown", ...) of leg
        ``leg`` (0 back, 1 front) among the records logged since record ``since`` (the
        engine's ``nev`` then)."""
        codes = {v: c for c, v in L.EVENT_KIND_NAMES.items()}
        if kind not in codes:
            raise ValueError(f"kind = {kind!r} is not allowed: must be one of {sorted(codes)}")
        ev = self.ev[since : min(self.nev, self.ev.shape[0])]
        m = (ev[:, L.EVR_KIND] == codes[kind]) & (ev[:, L.EVR_LEG] == int(leg))
        return ev[m, L.EVR_T].copy()

    def plant_events(self, since: int = 0) -> tuple[tuple[str, int], ...]:
        """The plant's events (kind name, leg) logged since record ``since``, in order
        (the controller's own events left out): the sequence of contact and joint modes a
        stretch of the run went through."""
        ev = self.ev[since : min(self.nev, self.ev.shape[0])]
        names = L.EVENT_KIND_NAMES
        own = (L.EK_CTRL_TOUCHDOWN, L.EK_CTRL_LIFTOFF, L.EK_CTRL_SWEEP)
        return tuple(
            (names[int(k)], int(g))
            for k, g in zip(ev[:, L.EVR_KIND], ev[:, L.EVR_LEG])
            if int(k) not in own
        )

    def recorded_state(self, i: int) -> tuple[float, ...]:
        """The state recorded at row ``i`` of the time series (sample ``i`` of a run that
        keeps its records), as the run took it (dependent coordinates projected)."""
        if not 0 <= i < self.n_out:
            raise ValueError(f"i = {i!r} is not allowed: must be in [0, {self.n_out - 1}]")
        return tuple(float(v) for v in self.out_s[i])

    def leg_state_record(self) -> np.ndarray:
        """The controller's leg states (back, front) at every sample recorded so far,
        (n, 2) int: where the controller switched, sample by sample."""
        return self.out_ls[: self.n_out, [L.RM_LEG_STATE_B, L.RM_LEG_STATE_F]].astype(int)

    def contact_mode(self, leg) -> int:
        """Plant contact mode of leg ``leg`` now, a code of
        :class:`~scoutsim.names.ContactMode` (0 flight, 1 stick, 2 slide, 3 strut)."""
        return int(self.mi[L.MI_CONTACT_B + int(leg)])

    def electrical_energy(self) -> float:
        """Electrical energy into both legs' motor terminals since the start [J] (NaN
        without the energy accounting)."""
        e = self.energy
        if not e.size:
            return math.nan
        return float(e[L.EN_ELECTRICAL] + e[L.NEN_LEG + L.EN_ELECTRICAL])

    def retune(self, **values: float) -> None:
        """Change the built-in Table I controller's set-points and gains from the next
        sample on: ``field=value`` for fields of
        :class:`~scoutsim.parameters.ControllerParameters` in :data:`RETUNABLE` (SI: rad,
        N m/rad, N m s/rad)."""
        for name, value in values.items():
            slot = RETUNABLE.get(name)
            if slot is None:
                raise ValueError(
                    f"retune: {name!r} is not allowed: must be one of {sorted(RETUNABLE)}"
                )
            self.C[slot] = value

    def set_leg_state(self, leg: int, state: int) -> None:
        """Put the built-in Table I controller's leg ``leg`` (0 back, 1 front) into leg
        state ``state`` (a code of :class:`~scoutsim.names.LegState`) for the next
        sample."""
        self.ls[int(leg)] = state

    def read_first_sensors(self) -> Sensors:
        """The readings of the run's first sample (what a controller's ``reset`` sees)."""
        return Sensors.from_vector(self.read_sensors())

    def read_sensors(self) -> np.ndarray:
        """The sensor readings (``layout.SN_*``, SI) of the next control sample ``k`` at the
        current state, into ``block.y`` and returned (that array): between two calls of
        :meth:`advance`, what the loop reads at the start of the next one, bit for bit
        (measurement model included); after a run that ended (a fall), the readings at
        its final state."""
        readings_at(
            self.k,
            self.s,
            self.P,
            self.mi,
            self.mf,
            self.cmd,
            self.status == L.ST_RUNNING and flag_is_set(self.hwork[HW_EVAL_KEPT]),
            self.block,
        )
        return self.block.y

    def discard_records(self):
        """Forget the samples, events and steps recorded so far (the state, modes and
        energy accumulator stay): for a caller that reads the engine's state itself
        between calls, so that the buffers of ``rows`` samples suffice however long it
        runs."""
        self.n_out = self.nev = 0
        self.stepc[0] = 0

    def carry_sensitivities(self, seed, parameters=None) -> None:
        """From now on, carry the derivatives of the extended state x = [state, toe
        anchors [m], held commands [N m], controller state, parameters] (rows:
        :data:`~scoutsim.simulation.sensitivities.EXTENDED_ROWS`) with respect to m
        variables: ``seed`` (NX x m) is dx/d(variables) now; :attr:`sensitivities` holds
        them as the run goes on. ``parameters``: None, or (dP, dC, dcp) for n_p parameters
        carried as the last n_p rows of x (constant along the run): their derivatives of
        the packed arrays
        (:func:`~scoutsim.simulation.parameter_rows.robot_parameter_derivatives`). A Python
        controller runs outside the compiled loop and is not differentiated: refused."""
        if self.bridge is not None:
            raise ValueError(
                "carry_sensitivities: a Python controller runs outside the compiled loop and "
                "is not differentiated (the built-in law and a CompiledController are)"
            )
        seed = np.asarray(seed, dtype=float)
        tan = engine_tangent(self, seed.shape[1], parameters)
        if seed.shape != tan.Phi.shape:
            raise ValueError(
                f"seed has shape {seed.shape}: must be ({tan.Phi.shape[0]}, m), one row per "
                "entry of the extended state"
            )
        tan.Phi[:] = seed
        self.tangent = tan

    @property
    def sensitivities(self) -> np.ndarray:
        """dx/d(variables) now (NX x m; see :meth:`carry_sensitivities`)."""
        return self.tangent.Phi

    def smoothness(self) -> dict:
        """What the carried sensitivities met so far
        (:func:`~scoutsim.simulation.sensitivities.smoothness`)."""
        return smoothness(self.tangent.info)

    def advance(self, k_stop: int):
        """Run control samples k .. k_stop - 1 under the control block's controller."""
        with_hook(self.tangent, self._method)
        args = (
            Plant(self.s, self.P, self.mi, self.mf, self.cmd),
            Control(self.C, self.ls, self.block),
            Span(
                self.k,
                min(k_stop, self.k_last + 1),
                self.k_last,
                float(self.dt),
                self.rtol,
                self.atol,
            ),
            Records(
                self.out_t,
                self.out_s,
                self.out_aux,
                self.out_ls,
                self.ev,
                self.stats,
                self.steps,
                self.stepc,
                self.energy,
                self.out_energy,
            ),
            Carry(self.hwork, self.armed, self.sfwork, self.ew, self.tangent),
            self.n_out,
            self.nev,
        )
        if self._entry is None:  # the argument types stay those of the first call
            self._entry = run_entry(self._method, args)
        nev_before = self.nev
        self.k, self.n_out, self.nev, self.status, self.t_now = self._entry(*args, self._method)
        if self.energy.size:
            if self.energy_start is None and self.n_out:
                self.energy_start = float(self.out_aux[0, L.A_ENERGY])
            new = self.ev[nev_before : min(self.nev, self.ev.shape[0])]
            self.impact_loss += float(
                new[np.isin(new[:, L.EVR_KIND], L.IMPACT_KINDS), L.EVR_V3].sum()
            )
        if self.nev > self.ev.shape[0]:
            # one control period logged more records than the buffer had left (the loop
            # makes room between periods, 64 rows at least): log_event dropped them but
            # counted them. Count them as lost, and go on writing right after the last row
            # kept (no empty rows in the table)
            self.event_records_lost += self.nev - self.ev.shape[0]
            self.nev = self.ev.shape[0]
        if self.nev > self.ev.shape[0] - 64:
            self.ev = np.concatenate([self.ev, np.zeros_like(self.ev)])
        if self.stepc[1] and self.stepc[0] > self.steps.shape[0] - STEP_HEADROOM:
            self.steps = np.concatenate([self.steps, np.zeros_like(self.steps)])

    def energy_flows(self) -> dict | None:
        """The run's accumulated energies [J] by name (``SimulationResult.energy_flows``),
        or None if the run did not account for them."""
        if not self.energy.size:
            return None
        out = {
            f"{name}_{leg}": float(self.energy[i * L.NEN_LEG + j])
            for i, leg in enumerate(L.LEG_NAMES)
            for j, name in enumerate(L.EN_LEG_NAMES)
        }
        out["battery_loss"] = float(self.energy[L.EN_BATTERY_LOSS])
        out["impacts"] = self.impact_loss
        out["mechanical_start"] = (
            self.energy_start
            if self.energy_start is not None
            else float(state_energy(self.s, self.P))
        )
        out["mechanical_end"] = float(state_energy(self.s, self.P))
        return out

    def outcome(self, interrupted: bool = False) -> str:
        if interrupted:
            return "interrupted"
        return "completed" if self.status == L.ST_RUNNING else L.STATUS_NAMES[self.status]

    def result(
        self,
        provenance: dict,
        interrupted: bool = False,
        extra_stats: dict | None = None,
        last_sample_t: float | None = None,
    ) -> SimulationResult:
        """The run as a result (``last_sample_t``: the time of the last sample when a
        RunStream has taken the samples out of the buffers)."""
        n = self.n_out
        m = min(self.nev, self.ev.shape[0])
        return SimulationResult(
            t=_kept(self.out_t, n),
            state=_kept(self.out_s, n),
            aux=_kept(self.out_aux, n),
            modes=_kept(self.out_ls, n),
            events=self.ev[:m, : L.NEVREC].copy(),  # (contiguous: a few hundred kB)
            event_states=self.ev[:m, L.NEVREC :].reshape(m, 2, L.NS).copy(),
            steps=(_kept(self.steps, int(self.stepc[0])) if self.stepc[1] else None),
            outcome=self.outcome(interrupted),
            # (a run stopped before its first sample, e.g. by Ctrl-C: where it started)
            t_end=float(
                self.t_now
                if self.status not in (L.ST_RUNNING, L.ST_CONTROLLER_ERROR)
                else self.out_t[n - 1]
                if n
                else last_sample_t
                if last_sample_t is not None
                else self.t_now
            ),
            stats={name: float(self.stats[i]) for i, name in enumerate(STAT_NAMES)}
            | (
                {"event_records_lost": float(self.event_records_lost)}
                if self.event_records_lost
                else {}
            )
            | (extra_stats or {}),
            provenance=provenance,
            energy_flows=self.energy_flows(),
            energy_series=(_kept(self.out_energy, n) if self.energy.size else None),
        )


def start_controller(engine: HybridEngine, plan, robot: RobotParameters, start):
    """Make the controller of ``plan`` (:func:`~scoutsim.control.dispatch.plan_controller`)
    ready to run ``engine`` from ``start``, as :func:`~scoutsim.simulation.simulator.simulate`
    does: a Python controller's :class:`~scoutsim.control.dispatch.PythonBridge`, the
    controller's ``reset`` with the first readings (a compiled controller's state array from
    its ``initial_state``, which a reset may set) and, for a
    :class:`~scoutsim.state.HybridState` start, its held torques (before the first
    readings) and its ``controller_state`` (after the reset). Keeps the plan and the bridge
    on the engine (``engine.plan``, ``engine.bridge``) and returns the bridge (None unless
    the controller is a Python one)."""
    if isinstance(start, HybridState):
        engine.cmd[:] = start.held_torques
    user = plan.controller
    bridge = None
    if plan.kind == "python":
        bridge = PythonBridge(user, plan.block, engine.cmd, engine.ls, plan.control_period)
    if user is not None and callable(getattr(user, "reset", None)):
        user.reset(robot, engine.read_first_sensors())
        if plan.kind == "compiled":  # a reset may set the controller's initial state
            plan.block.state[: user.initial_state.size] = user.initial_state
    if isinstance(start, HybridState):
        write_controller_state(plan, start.controller_state)
    engine.plan, engine.bridge = plan, bridge
    return bridge


def start_engine(
    start: InitialState | HybridState | None,
    duration: float,
    *,
    robot: RobotParameters | None = None,
    model: str = "II",
    controller=None,
    hold_commands: bool = False,
    sensors: SensorParameters | None = None,
    friction_coefficient: float | None = None,
    pitch_limit_deg: float = DEFAULT_PITCH_LIMIT_DEG,
    integrator: IntegratorSettings | None = None,
    energy: bool = False,
    rows: int | None = None,
) -> HybridEngine:
    """An engine at sample 0 of a run from ``start``, put together as
    :func:`~scoutsim.simulation.simulator.simulate` does it
    (:func:`~scoutsim.simulation.assembly.assemble`), for a caller that drives it sample by
    sample itself (``engine.advance(k)``, the commands in ``engine.cmd`` or the Table I
    set-points by :meth:`HybridEngine.retune`, the readings from ``engine.read_sensors()``):
    a learning environment (:mod:`scoutsim.envs`).

    Parameters
    ----------
    start : InitialState (in flight), HybridState (e.g. :func:`~scoutsim.state.standing_state`
        or ``result.hybrid_state(k)``), or None: the model's default start.
    duration : longest run [s] (the engine stops at it).
    robot, model, sensors, friction_coefficient, pitch_limit_deg, integrator, energy : as for
        :func:`~scoutsim.simulation.simulator.simulate` (``model`` "ideal", "I" or "II"; ``energy``: the accumulator
        ``engine.energy``, layout ``EN_*`` [J]).
    controller : any controller :func:`~scoutsim.simulation.simulator.simulate` takes
        (default: the Table I law), made ready by :func:`start_controller` (a
        :class:`~scoutsim.state.HybridState` start sets its held torques and its
        ``controller_state``); with ``hold_commands``, ControllerParameters that set only
        the leg angles of a start in flight and what the hip encoders read
        (``sense_motor_angle``).
    hold_commands : no controller runs: the hip torques ``engine.cmd`` [N m per physical
        leg] are held as the caller sets them (zero at first).
    rows : samples the time-series buffers hold (None: the whole run); a caller that calls
        :meth:`HybridEngine.discard_records` after every call of at most ``rows - 1``
        samples runs for as long as it likes in that memory.
    """
    if model not in ("ideal", "I", "II"):
        raise ValueError(f"model = {model!r} is not allowed: must be 'ideal', 'I' or 'II'")
    robot = validate_robot(robot if robot is not None else RobotParameters())
    plant = PlantOptions(friction_coefficient=friction_coefficient, pitch_limit_deg=pitch_limit_deg)
    plan = plan_controller(controller, model, robot, sensors)
    if plan.kind == "builtin":
        validate_parameters(robot, plan.parameters)
    elif hold_commands:
        raise TypeError(
            "with hold_commands, controller must be ControllerParameters (they set the "
            f"legs' start angles), not {type(controller).__name__}"
        )
    if start is not None and not isinstance(start, (InitialState, HybridState)):
        raise TypeError(
            f"start must be an InitialState, a HybridState or None, not {type(start).__name__}"
        )
    setup = assemble(
        robot, model, start, plan, plant=plant, integrator=integrator, hold_commands=hold_commands
    )
    engine = HybridEngine.assembled(setup, duration, rows=rows, energy=energy)
    if not hold_commands:
        start_controller(engine, plan, robot, start)
    return engine


def _kept(buffer: np.ndarray, n: int) -> np.ndarray:
    """The first ``n`` rows of an engine buffer for a result: a view when the run filled
    most of the buffer (the engine is dropped after the run: copying 10 s of samples
    took 2.4 ms of a 42 ms run), a copy when it ended early (a run that fell at 1 s of
    10 s would otherwise keep the whole buffer alive)."""
    return buffer[:n] if 2 * n >= buffer.shape[0] else buffer[:n].copy()
