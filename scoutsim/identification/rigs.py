"""Virtual bench rigs: the paper's hip-unit identification experiments (Sec. III), as
configurations of the same simulator (docs/identification.md).

Each rig runs the compiled hybrid model of :func:`scoutsim.simulate` (same equations,
integrator, events, stiction, actuator and 1 kHz controller) with the torso held by a
*clamp*: three extra constraint rows of the KKT system, ``ddx = ddy = ddtheta = 0``
(``robot_array(..., clamp_torso=True)``), at a height where the toes never reach the
ground. Nothing else is special-cased:

* :class:`FreeSwing` - "a known mass was placed at the toe, the leg was brought to a known
  angle and then it was left to rotate freely". The toe mass ``m_t`` is a point mass
  rigidly on the leg axis at ``l0`` from the hip (released below the horizontal, gravity
  and the centrifugal force both pull the toe outwards onto the leg's stop, so the leg
  spring plays no part); it is lumped into the leg body (mass, COM distance and inertia by
  the parallel-axis theorem, :func:`with_toe_mass`). The motor is back-driven through the
  gear train with its leads open (no current) or shorted (``0 = R_A i + K_w w_m``,
  back-EMF braking). Both legs are released at once from their own angles (the two hip
  units are independent while the torso is clamped).
* :class:`FlightSteps` - "the robot was placed so that both the front and back legs were
  in flight and various touchdown angles were commanded": the Table I controller's flight
  servo (sensing the motor-side angle, as on the robot) and the full actuator model, with
  the touchdown-angle command stepped at given times.
* :class:`Stall` - the torso and both legs held (two more rows, ``ddphi = 0``) and the
  maximum hip torque ``N eta K_T i_max`` commanded: the belt deflection ``alpha - phi``
  is what the motor encoder shows (the robot measured about 8 deg).

:func:`rig_log` turns a rig run into a log in the project's log format
(:mod:`scoutsim.validation.log_format`) with the sensor chain of :class:`RigNoise` (motor
encoder quantisation plus white angle noise, current-sense noise; seeded).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from .._version import __version__
from ..names import LEG_NAMES
from ..parameters import ControllerParameters, RobotParameters, validate_robot
from ..result.simulation_result import SimulationResult
from ..simulation.integrator import IntegratorSettings
from ..state import state_vector
from ..validation.experiment_log import ExperimentLog
from ..validation.measurement import torque_per_amp
from .bench import Bench, run_bench

__all__ = [
    "FreeSwing",
    "FlightSteps",
    "Stall",
    "RigNoise",
    "RIG_NAMES",
    "run_rig",
    "rig_log",
    "with_toe_mass",
    "HIP_PARAMETERS",
    "hip_parameters",
    "stall_deflection",
]

RIG_NAMES = ("free-swing", "flight-steps", "stall")

#: The Model II hip-unit parameters (docs/specification.md section 5) and the transmission-loss parameters
#: (docs/model.md), with their SI units: what the rigs exercise and identification fits.
HIP_PARAMETERS = {
    "drive_gear_inertia": "kg m^2",
    "driven_gear_inertia": "kg m^2",
    "joint_stiction": "N m",
    "joint_damping": "N m s/rad",
    "belt_stiffness": "N m/rad",
    "belt_damping": "N m s/rad",
    "gearbox_idle_loss_torque": "N m",
    "gearbox_load_loss_coefficient": "1",
}

#: Parameters fitted by default for each rig.
DEFAULT_PARAMS = {
    "free-swing": (
        "drive_gear_inertia",
        "driven_gear_inertia",
        "joint_stiction",
        "joint_damping",
        "belt_stiffness",
        "belt_damping",
    ),
    "flight-steps": (
        "drive_gear_inertia",
        "driven_gear_inertia",
        "joint_stiction",
        "joint_damping",
        "belt_stiffness",
        "belt_damping",
    ),
}


def hip_parameters(robot: RobotParameters) -> dict:
    """The :data:`HIP_PARAMETERS` values of ``robot`` (SI; [back, front] for a value that
    differs between the legs)."""
    return {
        k: (list(map(float, v)) if isinstance(v, tuple) else float(v))
        for k in HIP_PARAMETERS
        for v in (getattr(robot, k),)
    }


def _check(name, value, lo, hi, unit="", lo_open=False, hi_open=False, deg=False):
    f = math.degrees if deg else (lambda x: x)
    ok = (
        isinstance(value, (int, float))
        and math.isfinite(value)
        and (value > lo if lo_open else value >= lo)
        and (value < hi if hi_open else value <= hi)
    )
    if not ok:
        shown = f(value) if isinstance(value, (int, float)) else value
        raise ValueError(
            f"{name} = {shown!r}{' deg' if deg else (' ' + unit if unit else '')} "
            f"is not allowed: must be in {'(' if lo_open else '['}{f(lo):g}, "
            f"{f(hi):g}{')' if hi_open else ']'}{' deg' if deg else (' ' + unit if unit else '')}"
        )


@dataclass(frozen=True)
class FreeSwing:
    """Free-swing rig (paper Sec. III, first experiment set).

    release_angle_back, release_angle_front : leg angle phi at release [rad], relative to
        the clamped (level) torso; each in (-90, 90) deg (below the horizontal). 0 = the
        leg hangs at rest.
    toe_mass : point mass at the toe, per physical leg [kg] (>= 0).
    motor : "open" (leads open, no current) or "short" (leads shorted, back-EMF braking).
    duration : recorded time [s].
    clamp_height : torso COM height in the clamp [m] (toes must clear the ground).
    """

    release_angle_back: float = math.radians(60.0)
    release_angle_front: float = math.radians(-40.0)
    toe_mass: float = 1.0
    motor: str = "open"
    duration: float = 3.0
    clamp_height: float = 1.0
    name: str = field(default="free-swing", init=False)

    def __post_init__(self):
        for n in ("release_angle_back", "release_angle_front"):
            _check(
                f"free_swing.{n}",
                getattr(self, n),
                -math.pi / 2,
                math.pi / 2,
                lo_open=True,
                hi_open=True,
                deg=True,
            )
        _check("free_swing.toe_mass", self.toe_mass, 0.0, 100.0, "kg")
        if self.motor not in ("open", "short"):
            raise ValueError(
                f"free_swing.motor = {self.motor!r} is not allowed: must be 'open' or 'short'"
            )
        _check("free_swing.duration", self.duration, 0.0, 600.0, "s", lo_open=True)
        _check("free_swing.clamp_height", self.clamp_height, 0.0, 10.0, "m", lo_open=True)


@dataclass(frozen=True)
class FlightSteps:
    """Flight-step rig (paper Sec. III, second experiment set): torso held in the air, the
    Table I flight servo steps the legs between touchdown-angle commands.

    step_times : times [s] at which the commands change (first must be 0, increasing).
    angles_back, angles_front : touchdown-angle command [rad] from each step time on; each
        in (-90, 90) deg.
    duration : recorded time [s].
    clamp_height : torso COM height [m].
    initial_angle_back, initial_angle_front : leg angle at t = 0, at rest [rad] (None: the
        first command).
    """

    step_times: tuple = (0.0, 0.4, 0.8, 1.2)
    angles_back: tuple = tuple(math.radians(a) for a in (19.0, -15.0, 30.0, 0.0))
    angles_front: tuple = tuple(math.radians(a) for a in (21.0, 35.0, -10.0, 10.0))
    duration: float = 1.6
    clamp_height: float = 1.0
    initial_angle_back: float | None = 0.0
    initial_angle_front: float | None = 0.0
    name: str = field(default="flight-steps", init=False)

    def __post_init__(self):
        object.__setattr__(self, "step_times", tuple(float(x) for x in self.step_times))
        object.__setattr__(self, "angles_back", tuple(float(x) for x in self.angles_back))
        object.__setattr__(self, "angles_front", tuple(float(x) for x in self.angles_front))
        n = len(self.step_times)
        if n == 0 or self.step_times[0] != 0.0:
            raise ValueError("flight_steps.step_times is not allowed: must start at 0 s")
        if any(b <= a for a, b in zip(self.step_times, self.step_times[1:])):
            raise ValueError(
                f"flight_steps.step_times = {self.step_times} is not allowed: "
                "must be strictly increasing"
            )
        for nm in ("angles_back", "angles_front"):
            v = getattr(self, nm)
            if len(v) != n:
                raise ValueError(
                    f"flight_steps.{nm} has {len(v)} entries; must have one per step time ({n})"
                )
            for a in v:
                _check(
                    f"flight_steps.{nm}",
                    a,
                    -math.pi / 2,
                    math.pi / 2,
                    lo_open=True,
                    hi_open=True,
                    deg=True,
                )
        for nm in ("initial_angle_back", "initial_angle_front"):
            v = getattr(self, nm)
            if v is not None:
                _check(
                    f"flight_steps.{nm}",
                    v,
                    -math.pi / 2,
                    math.pi / 2,
                    lo_open=True,
                    hi_open=True,
                    deg=True,
                )
        _check("flight_steps.duration", self.duration, 0.0, 600.0, "s", lo_open=True)
        if self.step_times[-1] >= self.duration:
            raise ValueError(
                f"flight_steps.step_times: last step at {self.step_times[-1]} s is "
                f"not allowed: must be < duration = {self.duration} s"
            )
        _check("flight_steps.clamp_height", self.clamp_height, 0.0, 10.0, "m", lo_open=True)

    def commands(self, t) -> np.ndarray:
        """(n, 2) touchdown-angle command [rad] (back, front) at times ``t`` [s]."""
        t = np.asarray(t, dtype=float)
        k = np.searchsorted(np.asarray(self.step_times), t + 1e-9, side="right") - 1
        return np.column_stack([np.asarray(self.angles_back)[k], np.asarray(self.angles_front)[k]])


@dataclass(frozen=True)
class Stall:
    """Stall rig (paper Sec. III): torso and legs held, maximum hip torque applied.

    leg_angle : angle at which both legs are held [rad].
    torque : commanded hip torque per physical leg [N m] (None: the maximum
        N eta K_T i_max, what the amplifier can deliver at stall).
    duration : recorded time [s] (the belt creeps with time constant c_b / k_b = 0.57 s
        for Table II values, so a few seconds reach the steady deflection).
    clamp_height : torso COM height [m].
    """

    leg_angle: float = 0.0
    torque: float | None = None
    duration: float = 6.0
    clamp_height: float = 1.0
    name: str = field(default="stall", init=False)

    def __post_init__(self):
        _check(
            "stall.leg_angle",
            self.leg_angle,
            -math.pi / 2,
            math.pi / 2,
            lo_open=True,
            hi_open=True,
            deg=True,
        )
        if self.torque is not None:
            _check("stall.torque", self.torque, -1e4, 1e4, "N m")
        _check("stall.duration", self.duration, 0.0, 600.0, "s", lo_open=True)
        _check("stall.clamp_height", self.clamp_height, 0.0, 10.0, "m", lo_open=True)


@dataclass(frozen=True)
class RigNoise:
    """Sensor chain of a rig log [assumed defaults, docs/identification.md].

    encoder_counts_per_rev : motor encoder counts per motor revolution (quadrature; 2000 =
        a 500-line encoder); the reading is quantised to 2 pi / (counts N) at the leg
        (3.1e-5 rad for Scout II). 0 = no quantisation.
    angle_rad : white noise on the angle before quantisation [rad] (vibration, electrical
        noise).
    current_a : white current-sense noise [A].
    """

    encoder_counts_per_rev: int = 2000
    angle_rad: float = 5.0e-4
    current_a: float = 0.05

    def __post_init__(self):
        if not (isinstance(self.encoder_counts_per_rev, int) and self.encoder_counts_per_rev >= 0):
            raise ValueError(
                f"noise.encoder_counts_per_rev = {self.encoder_counts_per_rev!r} "
                "is not allowed: must be an integer >= 0"
            )
        _check("noise.angle_rad", self.angle_rad, 0.0, 1.0, "rad")
        _check("noise.current_a", self.current_a, 0.0, 100.0, "A")


def with_toe_mass(robot: RobotParameters, toe_mass: float) -> RobotParameters:
    """``robot`` with a point mass ``toe_mass`` [kg] rigidly at the toe (distance l0 from the
    hip on the leg axis) lumped into the leg body, per physical leg:
    m' = m + m_t, d' = (m d + m_t l0) / m', I' = I + m (d - d')^2 + m_t (l0 - d')^2."""
    if toe_mass == 0.0:
        return robot
    new: dict[str, list[float]] = {"leg_mass": [], "leg_com_distance": [], "leg_inertia": []}
    for leg in (0, 1):
        one = robot.leg(leg)
        m, d, i0, l0 = one.leg_mass, one.leg_com_distance, one.leg_inertia, one.leg_rest_length
        m2 = m + toe_mass
        d2 = (m * d + toe_mass * l0) / m2
        new["leg_mass"].append(m2)
        new["leg_com_distance"].append(d2)
        new["leg_inertia"].append(i0 + m * (d - d2) ** 2 + toe_mass * (l0 - d2) ** 2)
    return robot.replace(**{k: tuple(v) for k, v in new.items()})


def _clamped_state(clamp_height, phi_b, phi_f, robot):
    """The state vector of the clamped rig at the start: torso at ``clamp_height`` [m], level,
    legs at the angles ``phi_b``, ``phi_f`` [rad] and at their rest lengths, the Model II
    gear angles equal to them (belts relaxed), everything at rest."""
    l0b, l0f = robot.per_leg("leg_rest_length")
    for leg, phi, l0 in ((0, phi_b, l0b), (1, phi_f, l0f)):
        sL = robot.hip_offset(leg)
        if (
            clamp_height - l0 * math.cos(phi) <= 0.0
            or clamp_height - 0.5 * robot.torso_height <= 0.0
        ):
            raise ValueError(
                f"clamp_height = {clamp_height} m is not allowed: the "
                f"{LEG_NAMES[leg]} toe or the torso would touch the ground "
                f"(hip at x = {sL:+.3f} m); use a height > l0 + torso_height/2"
            )
    return state_vector(
        y=clamp_height,
        phi_back=phi_b,
        phi_front=phi_f,
        alpha_back=phi_b,
        alpha_front=phi_f,
        leg_length_back=l0b,
        leg_length_front=l0f,
    )


def run_rig(
    rig,
    robot: RobotParameters | None = None,
    *,
    model: str = "II",
    controller: ControllerParameters | None = None,
    integrator: IntegratorSettings | None = None,
    touchdown_commands=None,
    dt: float | None = None,
    derivatives=None,
) -> SimulationResult:
    """Run a bench rig (:class:`FreeSwing`, :class:`FlightSteps` or :class:`Stall`) on the
    simulator (see the module docstring).

    Parameters
    ----------
    rig : the rig configuration.
    robot : RobotParameters (default Scout II); for a free swing the toe mass is added here.
    model : transmission variant ("II" default; "I" and "ideal" run too).
    controller : ControllerParameters for the flight-step rig's Table I flight servo
        (default Table I); its control period is the sample period.
    integrator : IntegratorSettings (default: the reference tolerances).
    touchdown_commands : flight steps only: optional (n, 2) array of touchdown commands [rad]
        per control sample (overrides the rig's step schedule; used to replay a log).
    dt : sample / control period [s] (default: the controller's, 1 ms).
    derivatives : optional :class:`~scoutsim.simulation.sample_derivatives.SampleDerivatives` the run
        fills: the derivatives of its driven-gear angles and motor currents with respect to
        robot fields, carried with it.

    Returns
    -------
    SimulationResult with ``provenance["rig"]`` = the rig configuration.
    """
    robot = validate_robot(robot if robot is not None else RobotParameters())
    # the reference integrator (the fits' tests are calibrated on it; the ARK splitting
    # does not yet include the short-circuit back-EMF damping)
    integ = integrator or IntegratorSettings(method="dopri5")
    cparams = controller or ControllerParameters()
    dt = cparams.control_period if dt is None else float(dt)
    prov = {"rig": {"name": rig.name, **asdict(rig)}}
    if isinstance(rig, FreeSwing):
        rb = with_toe_mass(robot, rig.toe_mass)
        s0 = _clamped_state(rig.clamp_height, rig.release_angle_back, rig.release_angle_front, rb)
        return run_bench(
            rb,
            model,
            s0,
            rig.duration,
            bench=Bench(clamp_torso=True, motor_circuit=rig.motor),
            dt=dt,
            integrator=integ,
            provenance=prov,
            derivatives=derivatives,
        )
    if isinstance(rig, FlightSteps):
        n = int(round(rig.duration / dt)) + 1
        if touchdown_commands is None:
            td = rig.commands(np.arange(n) * dt)
        else:
            td = np.asarray(touchdown_commands, dtype=float)
            if td.shape != (n, 2):
                raise ValueError(
                    f"touchdown_commands has shape {td.shape}; must be ({n}, 2) "
                    "(one row per control sample of the rig's duration)"
                )
        change = np.flatnonzero(np.any(td[1:] != td[:-1], axis=1)) + 1
        schedule = [
            (int(k), {"touchdown_angle_back": td[k, 0], "touchdown_angle_front": td[k, 1]})
            for k in np.concatenate([[0], change])
        ]
        pb = td[0, 0] if rig.initial_angle_back is None else rig.initial_angle_back
        pf = td[0, 1] if rig.initial_angle_front is None else rig.initial_angle_front
        s0 = _clamped_state(rig.clamp_height, pb, pf, robot)
        return run_bench(
            robot,
            model,
            s0,
            rig.duration,
            bench=Bench(clamp_torso=True),
            controller=cparams,
            schedule=schedule,
            dt=dt,
            integrator=integ,
            provenance=prov | {"controller": asdict(cparams)},
            derivatives=derivatives,
        )
    if isinstance(rig, Stall):
        s0 = _clamped_state(rig.clamp_height, rig.leg_angle, rig.leg_angle, robot)
        taus = tuple(
            robot.leg(leg).max_leg_torque if rig.torque is None else rig.torque for leg in (0, 1)
        )
        return run_bench(
            robot,
            model,
            s0,
            rig.duration,
            bench=Bench(clamp_torso=True, clamp_legs=True),
            held_torques=taus,
            dt=dt,
            integrator=integ,
            provenance=prov,
            derivatives=derivatives,
        )
    raise TypeError(f"rig must be FreeSwing, FlightSteps or Stall, not {type(rig).__name__}")


def encoder_reading(
    angle, robot: RobotParameters, noise: RigNoise | None, rng, leg=0
) -> np.ndarray:
    """What the motor encoder reports for the motor-side angle ``angle`` [rad, leg side]:
    white noise, then quantisation to 2 pi / (counts N)."""
    a = np.asarray(angle, dtype=float)
    if noise is None:
        return a.copy()
    if noise.angle_rad > 0:
        a = a + rng.normal(0.0, noise.angle_rad, a.shape)
    if noise.encoder_counts_per_rev > 0:
        q = 2.0 * math.pi / (noise.encoder_counts_per_rev * robot.leg(leg).gear_ratio)
        a = q * np.round(a / q)
    return a


def rig_log(
    result: SimulationResult,
    noise: RigNoise | None = RigNoise(),
    seed=0,
    source: str | None = None,
    notes: str = "",
) -> ExperimentLog:
    """The log a rig run would have produced (project log format, plus rig columns).

    Columns: ``t``; ``pitch_rad`` = 0 and ``height_m`` = the clamp height (the clamp, not
    measured); ``phi_{back,front}_rad``: the motor-encoder angle (motor-side alpha at the
    leg, as on the robot) through :func:`encoder_reading`; ``dphi_..._rad_s``: its
    central difference (as a controller would estimate it); ``current_..._a`` with white
    noise; ``leg_state_...`` (0: flight); flight steps also ``touchdown_cmd_..._rad`` (the
    commanded touchdown angle). Metadata: ``rig`` (name), ``rig_config`` (the configuration,
    SI), ``encoder``, ``sensor_noise``, ``noise_seed``, ``synthetic`` and, since the data
    are made with known parameters, ``true_parameters`` (the hip-unit values used) and
    ``robot``.
    """
    prov = result.provenance
    rig = prov.get("rig")
    if not rig:
        raise ValueError("result is not a rig run (no provenance['rig']); use run_rig()")
    robot = RobotParameters(**prov["robot"])
    rng = np.random.default_rng(seed)
    t = result.t
    dt = float(prov["control_period_s"])
    cols = {
        "t": t,
        "pitch_rad": np.zeros_like(t),
        "height_m": np.full_like(t, float(rig["clamp_height"])),
    }
    for leg, nm in enumerate(LEG_NAMES):
        enc = encoder_reading(result.motor_angle(leg), robot, noise, rng, leg)
        cols[f"phi_{nm}_rad"] = enc
        cols[f"dphi_{nm}_rad_s"] = np.gradient(enc, dt)
    for leg, nm in enumerate(LEG_NAMES):
        i = np.asarray(result.motor_current(leg), dtype=float)
        if noise is not None and noise.current_a > 0:
            i = i + rng.normal(0.0, noise.current_a, i.shape)
        cols[f"current_{nm}_a"] = i
    for leg, nm in enumerate(LEG_NAMES):
        cols[f"leg_state_{nm}"] = result.leg_state(leg).astype(float)
    if rig["name"] == "flight-steps":
        fs = FlightSteps(**{k: v for k, v in rig.items() if k != "name"})
        td = fs.commands(t)
        cols["touchdown_cmd_back_rad"] = td[:, 0]
        cols["touchdown_cmd_front_rad"] = td[:, 1]
    meta = {
        "source": source
        or f"scoutsim {__version__} virtual {rig['name']} rig, model {prov.get('model')}",
        "synthetic": True,
        "notes": notes,
        "lowpass_hz": None,
        "rig": rig["name"],
        "rig_config": {k: v for k, v in rig.items() if k != "name"},
        "model": prov.get("model"),
        "encoder": "motor-side angle alpha (motor encoder), at the leg",
        "sensor_noise": None if noise is None else asdict(noise),
        "noise_seed": seed if (seed is None or isinstance(seed, int)) else str(seed),
        "torque_per_amp_nm_a": torque_per_amp(robot),
        "true_parameters": hip_parameters(robot),
        "robot": asdict(robot),
    }
    return ExperimentLog(columns=cols, meta=meta, path=None)


def stall_deflection(
    robot: RobotParameters | None = None,
    rig: Stall | None = None,
    integrator: IntegratorSettings | None = None,
) -> dict:
    """Run the stall rig and report the belt deflection (the robot measured about 8 deg, paper Sec. III).

    Returns a dict (SI, plus ``*_deg``): ``torque_nm`` (delivered hip torque per physical
    leg at stall), ``deflection_final_rad`` / ``_deg`` (at the end of the run),
    ``deflection_max_rad``, ``static_band_rad`` (the equilibria the static balance
    k_b (alpha - phi) = tau -+ N tau_s allows: stiction at the motor holds anywhere in
    this band), ``creep_time_constant_s`` (c_b / k_b) and the run itself (``result``).
    """
    robot = validate_robot(robot if robot is not None else RobotParameters())
    rig = rig or Stall()
    res = run_rig(rig, robot, integrator=integrator)
    b = res.belt_deflection("back")
    tau = float(res.hip_torque_applied("back")[-1])
    back = robot.leg("back")
    band = (
        (tau - back.gear_ratio * back.joint_stiction) / back.belt_stiffness,
        (tau + back.gear_ratio * back.joint_stiction) / back.belt_stiffness,
    )
    return {
        "torque_nm": tau,
        "deflection_final_rad": float(b[-1]),
        "deflection_final_deg": math.degrees(float(b[-1])),
        "deflection_max_rad": float(np.max(np.abs(b))),
        "deflection_max_deg": math.degrees(float(np.max(np.abs(b)))),
        "static_band_rad": band,
        "static_band_deg": tuple(math.degrees(x) for x in band),
        "creep_time_constant_s": back.belt_damping / back.belt_stiffness,
        "result": res,
    }
