"""The entry point: :func:`simulate` runs the hybrid model under a controller.

    result = scoutsim.simulate(robot, controller, initial_state, duration, model="II")

Parts are swappable: robot parameters (:class:`~scoutsim.parameters.RobotParameters`), the
transmission variant (``model``: "ideal", "I", "II", "passive"), the controller (the
compiled Table I law, or any object with ``command(t, sensors)``), the initial state and
the integrator settings (:class:`IntegratorSettings`).
"""

from __future__ import annotations

import math
import os
import time
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ._version import __version__
from .control.block import control_block
from .control.bounding import SCHEDULABLE, controller_array
from .control.dispatch import PythonBridge, plan_controller
from .control.protocol import ControllerError, failure_message
from .control.sensors import SensorParameters, Sensors
from .control.startup import StartupParameters, run_startup
from .model import layout as L
from .model.evaluate import NSTIFF
from .model.transmission import motor_mode_from_rate
from .model.packing import robot_array
from .model.rigid_body import state_energy
from .numerics.dopri5 import eval_workspace
from .loop import effective_method, first_readings, readings_at, run_entry
from .numerics.hybrid import (HW_EVAL_KEPT, HW_STEP, METHOD_ARK3, METHOD_ARK4, METHOD_AUTO,
                              METHOD_DOPRI5, NHW, STEP_HEADROOM)
from .numerics.stats import NSTAT, S_HMIN, STAT_NAMES
from .parameters import (ControllerParameters, Environment, RobotParameters,
                         validate_parameters, validate_robot)
from .result import SimulationResult
from .state import HybridState, InitialState, standing_state

_METHODS = {"dopri5": METHOD_DOPRI5, "ark3": METHOD_ARK3, "ark4": METHOD_ARK4}

__all__ = ["simulate", "IntegratorSettings", "HybridEngine", "ControllerError", "Sensors",
           "default_initial_state", "run_bench", "warm_up", "start_engine"]


#: default (rtol, atol) of each method when the settings leave them open
DEFAULT_TOLERANCES = {"dopri5": (1e-8, 1e-9), "ark3": (1e-5, 1e-6), "ark4": (1e-6, 1e-7)}
#: "auto" uses ARK3 for Model II only down to this rtol (a 3rd-order method is inefficient
#: at tighter tolerances, where the 5th-order DOPRI5 takes over)
AUTO_ARK_MIN_RTOL = 1e-7


@dataclass(frozen=True)
class IntegratorSettings:
    """Integrator and error control (adaptive steps with located events in every method).

    method : "auto" (default), "dopri5", "ark3" or "ark4".
        "dopri5": explicit Dormand-Prince 5(4), the reference (default rtol 1e-8 /
        atol 1e-9; the paper's Working Model runs used an adaptive Kutta-Merson integrator
        at 1e-10, and 1e-8 reproduces their gait metrics to better than 1e-4, see
        tests/numerics). "ark3" / "ark4": additive Runge-Kutta 3(2) / 4(3) with the
        Model II belt dampers (and stiff motor damping) implicit (scoutsim/numerics/ark.py),
        for the stiff Model II. "auto": Model II with ``rtol`` unset or >= 1e-7 -> "ark3"
        (default rtol 1e-5 / atol 1e-6, velocities 1e-5: about 10x faster than the
        reference, 10 s gait metrics within 3e-5 of the rtol 1e-10 reference,
        tests/test_simulation.py); every other case -> "dopri5".
    rtol, atol : relative / absolute local error tolerance (SI units of each state
        component); None = the method's default (:data:`DEFAULT_TOLERANCES`). The ARK
        methods apply ``atol`` to positions, angles and leg lengths and 10 x ``atol`` to
        the velocities (``ark.VELOCITY_ATOL_FACTOR``: a 0.1 s time scale between the two
        units).
    initial_step : first step guess [s].

    :meth:`resolve` gives the concrete settings a run uses (recorded in its provenance).
    """

    rtol: float | None = None
    atol: float | None = None
    initial_step: float = 1e-4
    method: str = "auto"

    def __post_init__(self):
        if self.method not in _METHODS and self.method != "auto":
            raise ValueError(f"integrator.method = {self.method!r} is not allowed: must be one "
                             f"of {sorted(_METHODS) + ['auto']}")
        for name in ("rtol", "atol", "initial_step"):
            v = getattr(self, name)
            if v is None and name != "initial_step":
                continue
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"integrator.{name} = {v!r} is not allowed: must be a "
                                 "finite number > 0")
        if self.rtol is not None and self.rtol < 1e-14:
            raise ValueError(f"integrator.rtol = {self.rtol} is not allowed: must be >= 1e-14")

    def resolve(self, model: str = "II") -> "IntegratorSettings":
        """The concrete method and tolerances for ``model``."""
        import dataclasses
        m = self.method
        if m == "auto":
            m = ("ark3" if model == "II" and (self.rtol is None or
                                              self.rtol >= AUTO_ARK_MIN_RTOL) else "dopri5")
        elif m != "dopri5" and model != "II":
            m = "dopri5"   # the ARK splitting exists for Model II's belts only
        rt, at = DEFAULT_TOLERANCES[m]
        return dataclasses.replace(self, method=m, rtol=rt if self.rtol is None else self.rtol,
                                   atol=at if self.atol is None else self.atol)


def _state_vector(init: InitialState, robot: RobotParameters,
                  ctrl: ControllerParameters | None, passive_angles, passive_world) -> np.ndarray:
    s = np.zeros(L.NS)
    vals = asdict(init)
    for name, v in vals.items():
        if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v)):
            raise ValueError(f"initial_state.{name} = {v!r} is not allowed: must be finite")
    if not (-math.pi / 2 < init.theta < math.pi / 2):
        raise ValueError(f"initial_state.theta = {math.degrees(init.theta):.1f} deg is not "
                         "allowed: must be in (-90, 90) deg")
    if ctrl is not None:
        td = (ctrl.touchdown_angle_back, ctrl.touchdown_angle_front)
    elif passive_world:
        td = (passive_angles[0] - init.theta, passive_angles[1] - init.theta)
    else:
        td = tuple(passive_angles)
    phib = td[0] if init.phi_back is None else init.phi_back
    phif = td[1] if init.phi_front is None else init.phi_front
    l0 = robot.leg_rest_length
    lb = l0 if init.leg_length_back is None else init.leg_length_back
    lf = l0 if init.leg_length_front is None else init.leg_length_front
    for name, v in (("leg_length_back", lb), ("leg_length_front", lf)):
        if not (0.0 < v <= l0):
            raise ValueError(f"initial_state.{name} = {v} m is not allowed: must be in "
                             f"(0, {l0}] m")
    s[:7] = [init.x, init.y, init.theta, phib, phif, phib, phif]
    s[7:14] = [init.dx, init.dy, init.dtheta, init.dphi_back, init.dphi_front,
               init.dphi_back, init.dphi_front]
    s[L.IL_B] = lb
    s[L.IL_F] = lf
    # both toes must start above ground (the run starts in double flight)
    for leg, name in ((0, "back"), (1, "front")):
        sL = (2 * leg - 1) * robot.half_hip_spacing
        g = init.theta + s[3 + leg]
        toe_y = init.y + sL * math.sin(init.theta) - s[L.IL_B + leg] * math.cos(g)
        if toe_y < 0.0:
            raise ValueError(f"initial_state.y = {init.y} m is not allowed: the {name} toe "
                             f"starts {-toe_y * 1000:.1f} mm below the ground; the run "
                             "starts in flight, raise y or change the leg angles")
    return s


def default_initial_state(model: str = "II", robot: RobotParameters | None = None,
                          passive_touchdown_angles=(0.0, 0.0)) -> InitialState:
    """The documented default start of ``model`` (see :class:`InitialState`).

    Parameters
    ----------
    model : {"II", "I", "ideal", "passive"}
        The model the start is for.
    robot : RobotParameters, optional
        The robot (default: Scout II); only the passive start depends on it (through its
        leg rest length l0).
    passive_touchdown_angles : (back, front) [rad]
        Passive model only: where its legs are placed (as for :func:`simulate`).

    Returns
    -------
    InitialState
        The controlled models: ``InitialState()``. The passive model: the same but 1 m/s
        forward, legs at the passive touchdown angles, and the COM height at which the
        lower toe clears the ground by the same margin as the lower toe of the controlled
        start (24.6 mm for Scout II: 0.348 m with vertical legs).
    """
    if model != "passive":
        return InitialState()
    # The controlled start is released in flight, torso level at y0, legs at the
    # controller's touchdown angles phi_td (19 / 21 deg from the torso normal): each toe is
    # l0 cos(phi_td) below its hip, so the lower one (the back leg, closer to vertical)
    # clears the ground by y0 - l0 cos(19 deg) = 24.6 mm, a 71 ms fall before touchdown.
    # The passive model has no flight servo: its legs are placed at the passive touchdown
    # angles (vertical by default), l0 cos(gamma) below the hips, so at the same y0 a
    # vertical leg's toe would clear the ground by 7 mm only. Raise the start by the
    # difference of the two toe drops: the passive robot then falls the same 24.6 mm to
    # its first touchdown. (With a level torso both hips are at y, so the hip spacing
    # does not enter, and world and torso-relative angles coincide.)
    robot = robot if robot is not None else RobotParameters()
    ctrl = ControllerParameters()
    l0 = robot.leg_rest_length
    start = InitialState()
    drop_controlled = l0 * max(math.cos(ctrl.touchdown_angle_back),
                               math.cos(ctrl.touchdown_angle_front))
    drop_passive = l0 * max(math.cos(a) for a in passive_touchdown_angles)
    return start.replace(y=start.y - drop_controlled + drop_passive, dx=1.0)


def fresh_modes(s: np.ndarray, P: np.ndarray):
    """Mode arrays (mi, mf) of a start from state ``s`` with both toes in flight; each
    motor joint's stick/slip mode from its gear rate by the same rule as after an impact
    (:func:`~scoutsim.model.transmission.motor_mode_from_rate`: slipping in the direction of
    motion; at rest stuck if it has stiction, else "slipping" with zero Coulomb torque)."""
    mi = np.zeros(L.NMI, dtype=np.int64)
    mf = np.zeros(L.NMF)
    for leg in range(2):
        mi[L.MI_MOTOR_B + leg] = motor_mode_from_rate(float(s[L.NQ + 5 + leg]), P)
        mi[L.MI_SLIDE_DIR_B + leg] = 1
    return mi, mf


def _resumed_modes(init: HybridState):
    """Mode arrays (mi, mf) and controller leg states of a run resumed at ``init``."""
    mi, mf = init.mode_arrays()
    return mi, mf, np.array(init.leg_states, dtype=np.int64)


class HybridEngine:
    """One run of the compiled hybrid model (:func:`scoutsim.loop.run`): its
    time-series buffers and everything carried from one call to the next (state, modes,
    controller states, step-size guess, ARK splitting, armed events). :func:`simulate` and
    the bench rigs (:mod:`scoutsim.identification.rigs`) drive it in chunks of control
    samples; cutting a run into chunks does not change it."""

    #: integrator steps the step buffer holds at first (about 6 s of a Model II run at the
    #: default tolerance: 1.3 steps per control period)
    STEP_ROWS = 8192

    def __init__(self, P, C, s, mi, mf, ls, duration: float, dt: float,
                 integrator: IntegratorSettings, record_steps: bool = False,
                 rows: int | None = None, energy: bool = False, *, block):
        self.P, self.C, self.s, self.mi, self.mf, self.ls = P, C, s, mi, mf, ls
        # the controller and the sensors (control/block.py, control/dispatch.py)
        self.block = block
        self.dt = dt
        self.integ = integrator
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
        self.out_t = np.zeros(n_total + 1)
        self.out_s = np.zeros((n_total + 1, L.NS))
        self.out_aux = np.zeros((n_total + 1, L.NAUX))
        self.out_ls = np.zeros((n_total + 1, L.NRM), dtype=np.int8)
        self.ev = np.zeros((max(1024, int(EVENT_ROWS_PER_S * duration) + 256), L.NEVBUF))
        # every integrator step if record_steps (numerics.events.record_step): room for
        # STEP_ROWS steps beyond the headroom one control period may need (np.zeros:
        # pages a run does not reach are never touched); doubled when it runs low
        self.steps = np.zeros((STEP_HEADROOM + self.STEP_ROWS if record_steps else 0,
                               L.NSTEPREC))
        self.stepc = np.array([0, 1 if record_steps else 0], dtype=np.int64)
        # the work-energy accounting (layout EN_*; empty: off), the touchdown impacts'
        # losses [J] and the mechanical energy [J] at the first sample
        self.energy = np.zeros(L.NEN if energy else 0)
        # the accumulator at every recorded sample (rows as out_t; (0, NEN): off)
        self.out_energy = np.zeros((n_total + 1 if energy else 0, L.NEN))
        self.impact_loss = 0.0
        self.energy_start = None
        self.stats = np.zeros(NSTAT)
        self.stats[S_HMIN] = np.inf
        self.armed = np.zeros(L.NEV, dtype=np.bool_)
        self.n_out = self.nev = self.k = 0
        self.event_records_lost = 0
        self.status = L.ST_RUNNING
        self._entry = None        # the compiled run loop for this engine's method
        self.t_now = 0.0

    @property
    def running(self) -> bool:
        return self.k <= self.k_last and self.status == L.ST_RUNNING

    def read_first_sensors(self) -> Sensors:
        """The readings of the run's first sample (what a controller's ``reset`` sees)."""
        first_readings(self.s, self.P, self.mi, self.mf, self.cmd, self.block)
        return Sensors.from_vector(self.block.y)

    def read_sensors(self) -> np.ndarray:
        """The sensor readings (``layout.SN_*``, SI) of the next control sample ``k`` at the
        current state, into ``block.y`` and returned (that array): between two calls of
        :meth:`advance`, what the loop reads at the start of the next one, bit for bit
        (measurement model included); after a run that ended (a fall), the readings at
        its final state."""
        readings_at(self.k, self.s, self.P, self.mi, self.mf, self.cmd,
                    self.status == L.ST_RUNNING and self.hwork[HW_EVAL_KEPT] > 0.5,
                    self.block)
        return self.block.y

    def discard_records(self):
        """Forget the samples, events and steps recorded so far (the state, modes and
        energy accumulator stay): for a caller that reads the engine's state itself
        between calls, so that the buffers of ``rows`` samples suffice however long it
        runs."""
        self.n_out = self.nev = 0
        self.stepc[0] = 0

    def advance(self, k_stop: int):
        """Run control samples k .. k_stop - 1 under the control block's controller."""
        args = (self.s, self.P, self.mi, self.mf, self.C, self.ls, self.cmd, self.k,
                min(k_stop, self.k_last + 1), self.k_last, self.dt, self.integ.rtol,
                self.integ.atol, self.block, self.hwork, self.out_t, self.out_s, self.out_aux,
                self.out_ls, self.n_out, self.ev, self.nev, self.stats, self.armed,
                self.sfwork, self.ew, self.steps, self.stepc, self.energy,
                self.out_energy)
        if self._entry is None:   # the argument types stay those of the first call
            self._method = effective_method(_METHODS.get(self.integ.method, METHOD_AUTO),
                                            int(self.P[L.P_MODEL]))
            self._entry = run_entry(self._method, args)
        nev_before = self.nev
        self.k, self.n_out, self.nev, self.status, self.t_now = self._entry(*args,
                                                                            self._method)
        if self.energy.size:
            if self.energy_start is None and self.n_out:
                self.energy_start = float(self.out_aux[0, L.A_ENERGY])
            new = self.ev[nev_before:min(self.nev, self.ev.shape[0])]
            self.impact_loss += float(new[new[:, L.EVR_KIND] == L.EK_TOUCHDOWN,
                                          L.EVR_V3].sum())
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
        out = {f"{name}_{leg}": float(self.energy[i * L.NEN_LEG + j])
               for i, leg in enumerate(L.LEG_NAMES) for j, name in enumerate(L.EN_LEG_NAMES)}
        out["battery_loss"] = float(self.energy[L.EN_BATTERY_LOSS])
        out["impacts"] = self.impact_loss
        out["mechanical_start"] = (self.energy_start if self.energy_start is not None else
                                   float(state_energy(self.s, self.P)))
        out["mechanical_end"] = float(state_energy(self.s, self.P))
        return out

    def outcome(self, interrupted: bool = False) -> str:
        if interrupted:
            return "interrupted"
        return "completed" if self.status == L.ST_RUNNING else L.STATUS_NAMES[self.status]

    def result(self, provenance: dict, interrupted: bool = False,
               extra_stats: dict | None = None,
               last_sample_t: float | None = None) -> SimulationResult:
        """The run as a result (``last_sample_t``: the time of the last sample when a
        RunStream has taken the samples out of the buffers)."""
        n = self.n_out
        m = min(self.nev, self.ev.shape[0])
        return SimulationResult(
            t=_kept(self.out_t, n), state=_kept(self.out_s, n),
            aux=_kept(self.out_aux, n), modes=_kept(self.out_ls, n),
            events=self.ev[:m, :L.NEVREC].copy(),      # (contiguous: a few hundred kB)
            event_states=self.ev[:m, L.NEVREC:].reshape(m, 2, L.NS).copy(),
            steps=(_kept(self.steps, int(self.stepc[0])) if self.stepc[1] else None),
            outcome=self.outcome(interrupted),
            # (a run stopped before its first sample, e.g. by Ctrl-C: where it started)
            t_end=float(self.t_now if self.status not in (L.ST_RUNNING,
                                                          L.ST_CONTROLLER_ERROR) else
                        self.out_t[n - 1] if n else
                        last_sample_t if last_sample_t is not None else self.t_now),
            stats={name: float(self.stats[i]) for i, name in enumerate(STAT_NAMES)}
            | ({"event_records_lost": float(self.event_records_lost)}
               if self.event_records_lost else {})
            | (extra_stats or {}),
            provenance=provenance, energy_flows=self.energy_flows(),
            energy_series=(_kept(self.out_energy, n) if self.energy.size else None))


def start_engine(start: InitialState | HybridState | None, duration: float, *,
                 robot: RobotParameters | None = None, model: str = "II",
                 controller: ControllerParameters | None = None, hold_commands: bool = False,
                 sensors: SensorParameters | None = None,
                 friction_coefficient: float | None = None, pitch_limit_deg: float = 60.0,
                 integrator: IntegratorSettings | None = None, energy: bool = False,
                 rows: int | None = None) -> HybridEngine:
    """An engine at sample 0 of a run from ``start``, put together as :func:`simulate` does
    it, for a caller that drives it sample by sample itself (``engine.advance(k)``, the
    commands in ``engine.cmd`` or the Table I set-points in ``engine.C``, the readings from
    ``engine.read_sensors()``): a learning environment (:mod:`scoutsim.envs`).

    Parameters
    ----------
    start : InitialState (in flight), HybridState (e.g. :func:`~scoutsim.state.standing_state`
        or ``result.hybrid_state(k)``), or None: the model's default start.
    duration : longest run [s] (the engine stops at it).
    robot, model, sensors, friction_coefficient, pitch_limit_deg, integrator, energy : as for
        :func:`simulate` (``model`` "ideal", "I" or "II"; ``energy``: the accumulator
        ``engine.energy``, layout ``EN_*`` [J]).
    controller : ControllerParameters of the built-in Table I law (default Table I); with
        ``hold_commands`` they set only the leg angles of a start in flight and what the
        hip encoders read (``sense_motor_angle``).
    hold_commands : no controller runs: the hip torques ``engine.cmd`` [N m per physical
        leg] are held as the caller sets them (zero at first).
    rows : samples the time-series buffers hold (None: the whole run); a caller that calls
        :meth:`HybridEngine.discard_records` after every call of at most ``rows - 1``
        samples runs for as long as it likes in that memory.
    """
    if model not in ("ideal", "I", "II"):
        raise ValueError(f"model = {model!r} is not allowed: must be 'ideal', 'I' or 'II'")
    robot = validate_robot(robot if robot is not None else RobotParameters())
    cparams = controller if controller is not None else ControllerParameters()
    validate_parameters(robot, cparams)
    mu = Environment(friction_coefficient=friction_coefficient).friction_for(robot)
    if not (0.0 < pitch_limit_deg < 90.0):
        raise ValueError(f"pitch_limit_deg = {pitch_limit_deg} is not allowed: must be in (0, 90)")
    plan = plan_controller(cparams, model, robot, sensors)
    if hold_commands:
        plan.block.ints[L.CB_KIND] = L.CTRL_HELD
    P = robot_array(robot, model, friction_coefficient=mu,
                    pitch_limit=math.radians(pitch_limit_deg))
    init = start if start is not None else default_initial_state(model, robot)
    if isinstance(init, HybridState):
        s = np.array(init.state)
        mi, mf, ls = _resumed_modes(init)
    elif isinstance(init, InitialState):
        s = _state_vector(init, robot, cparams, (0.0, 0.0), True)
        ls = np.zeros(2, dtype=np.int64)
        mi, mf = fresh_modes(s, P)
    else:
        raise TypeError("start must be an InitialState, a HybridState or None, not "
                        f"{type(init).__name__}")
    integ = (integrator or IntegratorSettings()).resolve(model)
    return HybridEngine(P, plan.C, s, mi, mf, ls, duration, plan.control_period, integ,
                        rows=rows, energy=energy, block=plan.block)


def _kept(buffer: np.ndarray, n: int) -> np.ndarray:
    """The first ``n`` rows of an engine buffer for a result: a view when the run filled
    most of the buffer (the engine is dropped after the run: copying 10 s of samples
    took 2.4 ms of a 42 ms run), a copy when it ended early (a run that fell at 1 s of
    10 s would otherwise keep the whole buffer alive)."""
    return buffer[:n] if 2 * n >= buffer.shape[0] else buffer[:n].copy()


def run_bench(robot: RobotParameters, model: str, start_state, duration: float, *,
              clamp_torso: bool = False, clamp_legs: bool = False,
              motor_circuit: str = "amplifier", controller: ControllerParameters | None = None,
              held_torques=None, schedule=None, dt: float = 1e-3,
              integrator: IntegratorSettings | None = None,
              provenance: dict | None = None) -> SimulationResult:
    """Run the hybrid model on a bench: the engine of :func:`simulate` with the rig options
    a hip-unit identification needs (:mod:`scoutsim.identification.rigs`).

    Parameters
    ----------
    robot, model : as for :func:`simulate`.
    start_state : (16,) state vector (layout ``STATE_NAMES``, SI); the modes are derived
        from it (no toe in contact; Model II joints stuck unless their gear turns).
    duration : simulated time [s]; dt : control / sample period [s].
    clamp_torso : the torso is held at rest (extra constraint rows); clamp_legs : the legs
        are held at their angles relative to the torso too (a stall test).
    motor_circuit : "amplifier" (the current amplifier), "open" or "short" (the motor
        leads open or shorted: no amplifier).
    controller : ControllerParameters: the compiled Table I law sets the commands; None:
        ``held_torques`` (back, front) [N m per physical leg, at the leg] are held for the
        whole run (zero if not given).
    schedule : optional list of (k, {field: value}): from control sample k on, the
        controller's set-points ``field`` (a key of ``control.bounding.SCHEDULABLE``:
        touchdown angles, sweep limits) [rad] take these values.
    integrator : IntegratorSettings (default: the reference, DOPRI5).
    """
    P = robot_array(robot, model, clamp_torso=clamp_torso, clamp_legs=clamp_legs,
                    motor_circuit=motor_circuit)
    C = controller_array(controller, robot)
    s = np.array(start_state, dtype=float)
    mi, mf = fresh_modes(s, P)
    integrator = (integrator or IntegratorSettings(method="dopri5")).resolve(model)
    eng = HybridEngine(P, C, s, mi, mf, np.zeros(2, dtype=np.int64), duration, dt,
                       integrator, block=control_block(
                           L.CTRL_BUILTIN if controller is not None else L.CTRL_HELD,
                           geom=SensorParameters().geometry_array(
                               robot, controller is not None and controller.sense_motor_angle)))
    if held_torques is not None:
        eng.cmd[:] = held_torques
    chunk = max(1, int(round(1.0 / dt)))
    sched = sorted(schedule or [], key=lambda e: e[0])
    for _, changes in sched:
        for field in changes:
            if field not in SCHEDULABLE:
                raise ValueError(f"schedule field {field!r} is not allowed: must be one of "
                                 f"{sorted(SCHEDULABLE)}")
    si = 0
    while eng.running:
        while si < len(sched) and sched[si][0] <= eng.k:
            for field, value in sched[si][1].items():
                eng.C[SCHEDULABLE[field]] = value
            si += 1
        k_stop = eng.k + chunk
        if si < len(sched):
            k_stop = min(k_stop, int(sched[si][0]))
        eng.advance(k_stop)
    return eng.result(dict(provenance or {}, model=model, robot=asdict(robot),
                           control_period_s=dt, integrator=asdict(integrator),
                           scoutsim_version=__version__, duration_s=duration))


#: bytes a run holds per control sample: time, state, outputs (float64) and modes (int8)
BYTES_PER_SAMPLE = 8 * (1 + L.NS + L.NAUX) + L.NRM
#: ... per integrator step when steps are recorded, and steps per sample counted for it
#: (measured 1.3 for Model II at the default tolerance and for Model I; 3 leaves room)
BYTES_PER_STEP = 8 * L.NSTEPREC
STEPS_PER_SAMPLE = 3
#: the event buffer: rows per second of run and bytes per row (HybridEngine)
EVENT_ROWS_PER_S = 200
BYTES_PER_EVENT = 8 * L.NEVBUF


def physical_memory_bytes() -> int | None:
    """This machine's physical memory [bytes], or None where the OS does not say."""
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):
        return None


def check_run_memory(duration: float, *, record_steps: bool = False, dt: float = 1e-3,
                     memory_bytes: int | None = None) -> int:
    """The memory a run of ``duration`` [s] needs for its time series [bytes]; ValueError
    if that is more than half of this machine's memory (``memory_bytes``, default: the
    physical memory), saying how long a run can be (a longer one can be split: resume from
    ``result.hybrid_state(-1)``)."""
    per_sample = (BYTES_PER_SAMPLE + (STEPS_PER_SAMPLE * BYTES_PER_STEP if record_steps else 0)
                  + EVENT_ROWS_PER_S * dt * BYTES_PER_EVENT)
    need = int(int(duration / dt + 2) * per_sample)
    have = physical_memory_bytes() if memory_bytes is None else memory_bytes
    if have is not None and need > have // 2:
        longest = (have // 2) / per_sample * dt
        raise ValueError(f"duration = {duration:g} s is not allowed on this machine: the run's "
                         f"time series would need {need / 1e9:.3g} GB of memory, more than half "
                         f"of its {have / 1e9:.3g} GB; at most about {longest:.4g} s per run "
                         "(stream it to disk: simulate(..., stream_to=DIR), scoutsim run "
                         "--stream; simulate(..., check_memory=False) tries anyway)")
    return need


#: bytes per control sample of a streamed run's tables on disk (time series and events),
#: with a margin: Parquet (zstd) of a 12 s Model II run takes 370 B per sample (the
#: doubles hardly compress), 536 B with the energy accounting's cumulative energies (10 s:
#: time series 506 B, events 30 B)
BYTES_PER_SAMPLE_ON_DISK = 700
#: simulated seconds per piece a streamed run writes (memory: about 4 MB per 10 s)
STREAM_CHUNK_SECONDS = 10.0


#: wall seconds per simulated second of each model with the default integrator: an upper
#: estimate for refusing absurd requests (measured on a 2-core virtual machine, one
#: core busy:
#: Model II 4.0-6.6 ms, Model I 2-3.6 ms, ideal 2-2.9 ms, passive 4.3 ms; the slower
#: figure doubled for a slower machine; benchmarks/bench_speed.py measures the speed)
WALL_S_PER_SIMULATED_S = {"II": 13e-3, "I": 7e-3, "ideal": 6e-3, "passive": 9e-3}


def expected_wall_time(duration: float, model: str = "II") -> float:
    """An upper estimate of the wall time [s] a run of ``duration`` [s] of ``model`` takes
    with the default integrator (:data:`WALL_S_PER_SIMULATED_S`)."""
    return duration * WALL_S_PER_SIMULATED_S.get(model, max(WALL_S_PER_SIMULATED_S.values()))


def check_stream_disk(duration: float, directory, *, record_steps: bool = False,
                      dt: float = 1e-3) -> int:
    """The disk space a streamed run of ``duration`` [s] needs for its tables [bytes] (an
    upper bound); ValueError if the file system of ``directory`` has less free space,
    saying how long a run fits."""
    import shutil
    per_sample = BYTES_PER_SAMPLE_ON_DISK * (1 + (STEPS_PER_SAMPLE if record_steps else 0))
    need = int((duration / dt + 2) * per_sample)
    d = Path(directory)
    while not d.exists() and d != d.parent:
        d = d.parent
    free = shutil.disk_usage(d).free
    if need > free:
        raise ValueError(f"duration = {duration:g} s is not allowed here: the streamed run's "
                         f"tables would need up to {need / 1e9:.3g} GB on disk, and {d} has "
                         f"{free / 1e9:.3g} GB free; at most about {free / per_sample * dt:.4g} "
                         "s fit (simulate(..., check_memory=False), scoutsim run "
                         "--no-size-check, tries anyway)")
    return need


def warm_up() -> float:
    """Make the compiled core ready in this process: load it from Numba's cache, compiling
    it first if it is not there (minutes on a first run; :func:`scoutsim.jit.core_is_compiled`
    tells which). Every later :func:`simulate` then runs at full speed from its first call.
    Returns the wall time it took [s]."""
    t0 = time.perf_counter()
    simulate(duration=1e-3)
    return time.perf_counter() - t0


def simulate(robot: RobotParameters | None = None, controller=None,
             initial_state: InitialState | None = None, duration: float = 10.0, *,
             model: str = "II", environment: Environment | None = None,
             integrator: IntegratorSettings | None = None,
             friction_coefficient: float | None = None,
             pitch_limit_deg: float = 60.0,
             passive_touchdown_angles=(0.0, 0.0), passive_touchdown_world: bool = True,
             progress: bool = False, chunk_seconds: float = 1.0,
             record_steps: bool = False, check_memory: bool = True,
             stream_to=None, keep_seconds: float | None = None,
             table_format: str | None = None, energy: bool = False,
             sensors: SensorParameters | None = None,
             startup: StartupParameters | None = None) -> SimulationResult:
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
    friction_coefficient : float, optional
        Shortcut for ``environment=Environment(friction_coefficient=...)``: Coulomb
        coefficient of the toe, ``inf`` = no slip (not together with ``environment``).
    pitch_limit_deg : float
        |pitch| [deg] that counts as a fall (docs/specification.md section 3).
    passive_touchdown_angles : (back, front) [rad]
        Massless-leg configuration only: where the legs are placed in flight.
    passive_touchdown_world : bool
        Massless-leg configuration only: angles from the world vertical (True) or relative
        to the torso (False).
    progress : bool
        Show a progress bar (tqdm) on stderr.
    chunk_seconds : float
        Simulated time [s] per call of the compiled loop (progress updates, interrupts);
        the result does not depend on it.
    record_steps : bool
        Also record every integrator step (``result.steps``: time, state and plant modes at
        the end of each step, layout ``STP_*``); off by default (a 10 s Model II run takes
        about 50 000 steps).
    check_memory : bool
        Refuse (ValueError) a run whose time series would not fit in this machine's memory
        (:func:`check_run_memory`) before allocating anything; False to try anyway.
        A streamed run is checked against the free disk space instead
        (:func:`check_stream_disk`).
    stream_to : directory, optional
        Stream the run to this directory as it is computed (:mod:`scoutsim.streaming`):
        the ``timeseries``, ``events`` (and ``steps``) tables and a manifest, written chunk
        by chunk, so the memory a run needs does not grow with its duration. The returned
        result then holds only the last ``keep_seconds`` of the run (outcome, end time and
        statistics are the whole run's); ``SimulationResult.load(stream_to)`` reads all.
    keep_seconds : float, optional
        With ``stream_to``: seconds at the end of the run kept in memory and returned
        (default :data:`scoutsim.streaming.DEFAULT_KEEP_SECONDS`, 60 s).
    table_format : {"parquet", "csv"}, optional
        With ``stream_to``: the tables' format (default Parquet if pyarrow is installed).
    energy : bool
        Account for every power flow of the model over the whole run (electrical energy,
        copper and transmission losses, hip work, joint, belt, leg and toe friction and
        damping, constraint work; docs/model.md "Work-energy balance"), integrated on every
        integrator step: ``result.energy_flows``, ``result.energy_balance()``. The motion is
        the same bit for bit; the run takes longer (three more evaluations per step:
        10 s of Model II 1.65x, of Model I 1.28x).
    sensors : SensorParameters, optional
        How the robot's sensors measure (:class:`~scoutsim.control.sensors.SensorParameters`:
        noise, bias, resolution and delay per channel, seeded; a robot file's
        ``[sensors]``: :func:`~scoutsim.control.sensors.load_sensors`); default: ideal
        sensors. Every controller, the built-in one too, sees the sensors' readings.
    startup : StartupParameters, optional
        With ``initial_state="standing"`` only: the start-up's parameters (default
        ``StartupParameters()``).

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
    robot = validate_robot(robot if robot is not None else RobotParameters())
    integ = (integrator or IntegratorSettings()).resolve(model)
    if environment is not None and friction_coefficient is not None:
        raise ValueError("friction_coefficient and environment are not allowed together: "
                         "give the floor's friction in environment=Environment(...)")
    if environment is None:
        environment = Environment(friction_coefficient=friction_coefficient)
    friction_coefficient = environment.friction_for(robot)
    if not (isinstance(duration, (int, float)) and math.isfinite(duration) and duration > 0):
        raise ValueError(f"duration = {duration!r} s is not allowed: must be a finite number > 0")
    if not (0.0 < pitch_limit_deg < 90.0):
        raise ValueError(f"pitch_limit_deg = {pitch_limit_deg} is not allowed: must be in (0, 90)")
    if stream_to is None and (keep_seconds is not None or table_format is not None):
        raise ValueError("keep_seconds and table_format are only allowed with stream_to")
    if check_memory and stream_to is None:
        check_run_memory(duration, record_steps=record_steps)

    plan = plan_controller(controller, model, robot, sensors)
    cparams = plan.parameters
    if plan.kind == "builtin":
        validate_parameters(robot, cparams)

    P = robot_array(robot, model, friction_coefficient=friction_coefficient,
                    passive_touchdown_angles=passive_touchdown_angles,
                    passive_touchdown_world=passive_touchdown_world,
                    pitch_limit=math.radians(pitch_limit_deg))
    dt = plan.control_period
    initial_state, startup = _named_start(initial_state, startup, model, robot, cparams,
                                          plan.controller)
    init = initial_state or default_initial_state(model, robot, passive_touchdown_angles)
    resume = isinstance(init, HybridState)
    if resume:
        s = np.array(init.state)
    elif isinstance(init, InitialState):
        s = _state_vector(init, robot, None if model == "passive" else
                          (cparams or ControllerParameters()),
                          passive_touchdown_angles, passive_touchdown_world)
    else:
        raise TypeError("initial_state must be an InitialState, a HybridState, 'flight' "
                        f"or 'standing', not {type(init).__name__}")

    if resume:
        mi, mf, ls = _resumed_modes(init)
    else:
        ls = np.zeros(2, dtype=np.int64)
        mi, mf = fresh_modes(s, P)
    chunk = max(1, int(round(chunk_seconds / dt)))
    stream = None
    if stream_to is not None:
        from .streaming import DEFAULT_KEEP_SECONDS, RunStream
        stream = RunStream(stream_to, fmt=table_format, keep_seconds=(
            DEFAULT_KEEP_SECONDS if keep_seconds is None else keep_seconds))
        if check_memory:
            check_stream_disk(duration, stream.dir, record_steps=record_steps, dt=dt)
        # fewer, larger pieces: each costs ~5 ms of table writing
        chunk = max(chunk, int(round(STREAM_CHUNK_SECONDS / dt)))
    eng = HybridEngine(P, plan.C, s, mi, mf, ls, duration, dt, integ, record_steps,
                       rows=None if stream is None else chunk + 2, energy=energy,
                       block=plan.block)
    user_ctrl = plan.controller
    bridge = None
    if plan.kind == "python":
        bridge = PythonBridge(user_ctrl, plan.block, eng.cmd, ls, dt)
    if user_ctrl is not None and callable(getattr(user_ctrl, "reset", None)):
        user_ctrl.reset(robot, eng.read_first_sensors())
        if plan.kind == "compiled":    # a reset may set the controller's initial state
            plan.block.state[:user_ctrl.initial_state.size] = user_ctrl.initial_state
    wall0 = time.perf_counter()
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=round(duration, 3), unit="s", unit_scale=False, desc=f"Model {model}",
                   leave=False, bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} s [{elapsed}<{remaining}]")
    interrupted = False
    started = None       # the start-up from standing: its StartupRecord
    written = True       # a streamed run's tables took every piece so far
    try:
        if startup is not None:
            started = run_startup(eng, startup, cparams)
            if bar is not None:
                bar.update(round(eng.k * dt, 6))
            written = stream is None or stream.take(eng)
        while written and eng.running:
            k_prev = eng.k
            eng.advance(eng.k + chunk)
            if bridge is not None and bridge.interrupted:
                raise KeyboardInterrupt
            if stream is not None and not stream.take(eng):
                break       # the disk refused a piece (full): outcome "write_failed", below
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
        "robot": asdict(robot),
        "controller": (asdict(cparams) if cparams is not None else None),
        "controller_kind": plan.label,
        "initial_state": asdict(init) | ({"kind": "standing"} if startup is not None else
                                         {"kind": "hybrid_state"} if resume else {}),
        "integrator": asdict(integ),
        "duration_s": duration,
        "friction_coefficient": (None if math.isinf(friction_coefficient) else friction_coefficient),
        "pitch_limit_deg": pitch_limit_deg,
        "passive_touchdown_angles_rad": list(passive_touchdown_angles),
        "passive_touchdown_world": passive_touchdown_world,
        "control_period_s": dt,
    }
    if startup is not None:
        provenance["startup"] = (started.to_dict() if started is not None else
                                 {"parameters": asdict(startup.resolved(cparams))})
    if sensors is not None and not sensors.is_ideal():
        provenance["sensors"] = sensors.as_dict()
    error = failure = None
    if eng.status == L.ST_CONTROLLER_ERROR and not interrupted:
        status = 0
        if bridge is not None and bridge.failure is not None:
            failure = bridge.failure
        else:      # a compiled controller: its status, or the torques it wrote
            failure = (eng.k, tuple(float(v) for v in eng.cmd), None)
            status = int(plan.block.ints[L.CB_STATUS])
        k_fail, returned, exc = failure
        message = failure_message(user_ctrl, k_fail, dt, returned, exc, status)
        provenance["controller_error"] = message
        error = ControllerError(message, controller=user_ctrl, t=k_fail * dt, sample=k_fail,
                                returned=returned)
    if stream is None:
        result = eng.result(provenance, interrupted, {"wall_time_s": wall})
        if error is not None:
            error.result = result
            raise error from failure[2]
        return result
    try:
        if stream.write_error is None:
            stream.take(eng)   # a Ctrl-C between the compiled call and take(): its rows
    except BaseException:
        stream.abort()
        raise
    whole = eng.result(provenance, interrupted, {"wall_time_s": wall},
                       last_sample_t=stream.last_sample_t)
    if stream.write_error is not None:
        whole.outcome = "write_failed"
        warnings.warn(f"simulate: the streamed run's tables could not be written to "
                      f"{stream.dir} ({stream.write_error}); the run stopped at t = "
                      f"{whole.t_end:g} s: the result holds its last "
                      f"{stream.keep_seconds:g} s, result.provenance['stream'] says what the "
                      "tables kept", RuntimeWarning, stacklevel=2)
    kept = stream.finish(whole, partial=interrupted or stream.write_error is not None
                         or error is not None)
    if error is not None:
        error.result = kept
        raise error from failure[2]
    return kept


#: the starts ``simulate(initial_state=...)`` knows by name
NAMED_STARTS = ("flight", "standing")


def _named_start(initial_state, startup, model, robot, cparams, user_ctrl):
    """Resolve a start given by name: (initial state or None for the default, start-up
    parameters or None). "flight": the default start; "standing": the robot at rest
    (:func:`~scoutsim.state.standing_state`) and the start-up of
    :mod:`scoutsim.control.startup`, which needs the built-in Table I controller."""
    if not isinstance(initial_state, str):
        if startup is not None:
            raise ValueError("startup is only allowed with initial_state='standing'")
        return initial_state, None
    if initial_state not in NAMED_STARTS:
        raise ValueError(f"initial_state = {initial_state!r} is not allowed: must be an "
                         f"InitialState, a HybridState or one of {list(NAMED_STARTS)}")
    if initial_state == "flight":
        if startup is not None:
            raise ValueError("startup is only allowed with initial_state='standing'")
        return None, None
    if user_ctrl is not None:
        raise ValueError("initial_state = 'standing' is not allowed with a user controller "
                         f"({type(user_ctrl).__name__}): the start-up runs the built-in "
                         "Table I controller (pass ControllerParameters or None)")
    if model == "passive" or cparams is None:
        raise ValueError("initial_state = 'standing' is not allowed with model = "
                         f"{model!r}: the standing robot is held and set going by the "
                         "bounding controller (model 'ideal', 'I' or 'II')")
    if startup is None:
        startup = StartupParameters()
    elif not isinstance(startup, StartupParameters):
        raise TypeError(f"startup must be StartupParameters, not {type(startup).__name__}")
    return standing_state(robot, model, cparams), startup

