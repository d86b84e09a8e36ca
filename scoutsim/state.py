"""The robot's state at the start of a run: a physical start (:class:`InitialState`) or the
hybrid state of a control sample (:class:`HybridState`), from which a run resumes (to the
integration tolerance, not bit for bit: see :class:`HybridState`). Used by
:func:`scoutsim.simulate` and :meth:`SimulationResult.hybrid_state`.

:data:`STATE_NAMES` names the components of the state vector; :func:`state_vector` builds
one from its components by name and :func:`state_index` finds a component, so the layers
above read and write a state vector without its layout.

:func:`standing_state` is the robot at rest on its four legs (the start of
``simulate(..., initial_state="standing")``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ._core.model import layout as L
from .parameters import ControllerParameters, RobotParameters

__all__ = [
    "InitialState",
    "HybridState",
    "standing_state",
    "standing_leg_compression",
    "standing_leg_compressions",
    "STATE_NAMES",
    "state_index",
    "state_vector",
]

#: The components of the state vector, in its order (SI: m, rad, m/s, rad/s): torso x, y,
#: pitch theta, leg angles phi and Model II driven-gear angles alpha (back, front; relative
#: to the torso), their rates (``d`` + name), leg lengths (back, front).
STATE_NAMES = L.STATE_NAMES


def state_index(name: str) -> int:
    """Index of the component ``name`` (:data:`STATE_NAMES`) in a state vector; ValueError
    for an unknown name."""
    try:
        return L.STATE_NAMES.index(name)
    except ValueError:
        raise ValueError(
            f"name = {name!r} is not allowed: must be one of {list(L.STATE_NAMES)}"
        ) from None


def state_vector(**components: float) -> np.ndarray:
    """A state vector (:data:`STATE_NAMES`, SI) with the named components set and every
    other one zero, e.g. ``state_vector(y=0.4, phi_back=0.1, leg_length_back=0.323)``;
    ValueError for an unknown name."""
    s = np.zeros(L.NS)
    for name, value in components.items():
        s[state_index(name)] = value
    return s


@dataclass(frozen=True)
class InitialState:
    """Initial state of the robot (SI units, angles in rad; docs/specification.md section 1 conventions).

    The default is how such a robot is set going into a bound: released in flight with
    both legs at their touchdown angles, torso level at a COM height of 0.33 m (toes about
    2 cm above the ground), moving forward at 1.2 m/s with the nose rising at 150 deg/s,
    the motion the robot has after its front legs push off in its own bound (at front
    lift-off the cycle pitches up at 90-100 deg/s and moves at 1.3-1.6 m/s). The controller
    has no torso feedback, so a start without pitch motion tends not to enter bounding;
    from this one, ideal, Model I and Model II all reach their bounding cycles, and so do
    all their neighbours (speed 1.0-1.4 m/s, pitch rate 100-200 deg/s, height 0.32-0.35 m)
    on the default floor (docs/model.md, "Default start and floor"). Leg lengths default
    to l0.
    """

    x: float = 0.0
    y: float = 0.33
    theta: float = 0.0
    dx: float = 1.2
    dy: float = 0.0
    dtheta: float = math.radians(150.0)
    phi_back: float | None = None
    phi_front: float | None = None
    dphi_back: float = 0.0
    dphi_front: float = 0.0
    leg_length_back: float | None = None
    leg_length_front: float | None = None

    def replace(self, **changes) -> InitialState:
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True)
class HybridState:
    """The hybrid state at a control sample: where a run can be resumed.

    Unlike :class:`InitialState` (a physical start in double flight, the rest derived), it
    holds the continuous state and every mode the model carries from one sample to the
    next, so Model II gear angles, legs in stance and the controller's leg states can be
    set (used by :func:`scoutsim.analysis.controlled_orbit.controlled_fixed_point`). Take one
    from a run with :meth:`SimulationResult.hybrid_state`; a run from it starts at t = 0.

    A resumed run continues the original to the integration tolerance, not bit for bit: it
    starts from the sample's state and modes but not from the integrator's own state (its
    step-size guess, the ARK splitting, the kept evaluation), so its steps differ. Measured
    over 1 s from sample 1500 of the default 3 s Model II run: largest difference 1.4e-3
    rad/s in a leg rate and 3.5e-8 rad in pitch with the default ARK3 (rtol 1e-5); 3.6e-8
    in any component with DOPRI5 (rtol 1e-8).

    state : (16,) [x, y, theta, phi_b, phi_f, alpha_b, alpha_f, their rates, l_b, l_f]
        (SI; layout.py; dependent coordinates are projected at the start).
    leg_states : controller leg states (back, front): 0 flight, 1 stance-retraction,
        2 stance-brake.
    contact_modes : plant toe modes (back, front): 0 flight, 1 stick, 2 slide, 3 strut.
    motor_modes : Model II motor-joint modes (back, front): 0 stuck, +1 / -1 slipping in
        that direction.
    slide_directions : +1 / -1, direction of a sliding toe (back, front).
    toe_anchors : world x [m] of pinned (stick / strut) toes (back, front).
    controller_state : the controller's own state before its command at this sample (floats,
        in the controller's units): a :class:`~scoutsim.control.compiled.CompiledController`'s
        state array, or what a Python controller's ``get_state()`` returns
        (:mod:`scoutsim.control.protocol`); empty: the controller starts from its own
        initial state, as in any run. The built-in Table I law keeps only ``leg_states``.
    held_torques : the hip torques [N m] (back, front, per physical leg) held from the
        sample before: what the motor-current and IMU readings of this sample see before
        the controller's new command (no effect on the Table I law with ideal sensors,
        which reads the encoders and leg lengths only).
    """

    state: tuple
    leg_states: tuple = (0, 0)
    contact_modes: tuple = (0, 0)
    motor_modes: tuple = (0, 0)
    slide_directions: tuple = (1, 1)
    toe_anchors: tuple = (0.0, 0.0)
    controller_state: tuple = ()
    held_torques: tuple = (0.0, 0.0)

    def __post_init__(self):
        s = np.asarray(self.state, dtype=float)
        if s.shape != (L.NS,) or not np.all(np.isfinite(s)):
            raise ValueError(
                f"HybridState.state must be {L.NS} finite numbers, got shape {s.shape}"
            )
        object.__setattr__(self, "state", tuple(float(v) for v in s))
        allowed = {
            "leg_states": (L.LS_FLIGHT, L.LS_RETRACTION, L.LS_BRAKE),
            "contact_modes": (L.FLIGHT, L.STICK, L.SLIDE, L.STRUT),
            "motor_modes": (L.STUCK, L.SLIP_POS, L.SLIP_NEG),
            "slide_directions": (1, -1),
        }
        for name, ok in allowed.items():
            v = tuple(int(x) for x in getattr(self, name))
            if len(v) != 2 or any(x not in ok for x in v):
                raise ValueError(
                    f"HybridState.{name} = {getattr(self, name)!r} is not "
                    f"allowed: two values from {sorted(ok)}"
                )
            object.__setattr__(self, name, v)
        self._finite_pair("toe_anchors", "two finite positions [m]")
        c = np.asarray(self.controller_state, dtype=float).ravel()
        if not np.all(np.isfinite(c)):
            raise ValueError(
                f"HybridState.controller_state = {self.controller_state!r} is not allowed: "
                "finite numbers only"
            )
        object.__setattr__(self, "controller_state", tuple(float(v) for v in c))
        self._finite_pair("held_torques", "two finite hip torques [N m]")

    def _finite_pair(self, name: str, what: str) -> None:
        """Field ``name`` as a tuple of two finite floats; ValueError saying ``what`` it
        must be otherwise."""
        v = tuple(float(x) for x in getattr(self, name))
        if len(v) != 2 or not all(math.isfinite(x) for x in v):
            raise ValueError(f"HybridState.{name} = {getattr(self, name)!r} is not allowed: {what}")
        object.__setattr__(self, name, v)

    def mode_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """The compiled model's mode arrays of this state: (mi, mf), layout ``MI_*`` (toe
        contact, motor-joint and slide-direction modes) and ``MF_*`` (toe anchors [m])."""
        mi = np.zeros(L.NMI, dtype=np.int64)
        mf = np.zeros(L.NMF)
        for leg in range(2):
            mi[L.MI_CONTACT_B + leg] = self.contact_modes[leg]
            mi[L.MI_MOTOR_B + leg] = self.motor_modes[leg]
            mi[L.MI_SLIDE_DIR_B + leg] = self.slide_directions[leg]
            mf[L.MF_ANCHOR_B + leg] = self.toe_anchors[leg]
        return mi, mf


# -----------------------------------------------------------------------------------------
# the robot standing at rest
# -----------------------------------------------------------------------------------------
def standing_leg_compressions(robot: RobotParameters | None = None) -> tuple[float, float]:
    """Compressions l0 - l [m] of the (back, front) virtual legs of the robot standing at
    rest on vertical legs. Vertical legs put the spring forces and the leg bodies' weight
    through the hips, so the hips hold no torque and the two springs carry the whole weight
    m g (m: torso and every leg) in the ratio the moments about the robot's centre of mass
    set: F_back = m g (h_f - x_c) / (h_f - h_b), F_front = m g (x_c - h_b) / (h_f - h_b),
    with h the hips' positions along the torso axis from the torso COM
    (:meth:`~scoutsim.parameters.RobotParameters.hip_offset`) and x_c = n (m_lb h_b +
    m_lf h_f) / m the robot's COM there; each leg is compressed by F / (n k) (n physical legs
    of stiffness k; Table III). Equal legs and a COM midway: half the weight each, m g /
    (2 n k); Scout II: 24.745 kg x 9.81 m/s^2 / (2 x 7040 N/m) = 17.2 mm."""
    robot = robot if robot is not None else RobotParameters()
    n = robot.legs_per_virtual_leg
    hb, hf = robot.hip_offset(0), robot.hip_offset(1)
    mb, mf = robot.per_leg("leg_mass")
    kb, kf = robot.per_leg("leg_stiffness")
    weight = robot.total_mass * robot.gravity
    xc = n * (mb * hb + mf * hf) / robot.total_mass
    fb = weight * ((hf - xc) / (hf - hb))
    ff = weight * ((xc - hb) / (hf - hb))
    return fb / (n * kb), ff / (n * kf)


def standing_leg_compression(robot: RobotParameters | None = None) -> float:
    """Compression l0 - l [m] of each virtual leg of a robot with equal legs and its COM
    midway standing level on vertical legs (:func:`standing_leg_compressions`, which gives
    the two legs of any robot): m g / (2 n k). Scout II: 17.2 mm."""
    back, front = standing_leg_compressions(robot)
    if back != front:
        raise ValueError(
            f"the standing legs are compressed unequally (back {back:.4g} m, "
            f"front {front:.4g} m): use standing_leg_compressions(robot)"
        )
    return back


def standing_state(
    robot: RobotParameters | None = None,
    model: str = "II",
    controller: ControllerParameters | None = None,
    x: float = 0.0,
) -> HybridState:
    """The robot at rest on its four legs: a static equilibrium.

    Both virtual legs are vertical, with their toes pinned on the ground (contact mode
    stick) below the hips, each leg compressed by :func:`standing_leg_compressions` so that
    the two springs carry the whole weight; the torso is level when the legs are equal and
    the COM midway (phi = 0, the Table I sweep limit), and otherwise pitched to the angle
    theta at which both toes reach the ground (sin theta = (l_f - l_b) / (h_f - h_b), the
    legs at phi = -theta);
    every velocity is zero. On vertical legs the spring force passes through the hip and
    the leg bodies' weight acts along the legs, so the hips hold no torque: the Model II
    belts are undeflected (gear angle alpha = phi = 0) and the motor joints stuck by their
    stiction. The controller's leg states are stance-brake, whose PD law about the sweep
    limit (Table I: 0 deg, the standing angle; the start-up from standing holds 0 deg
    whatever the sweep limits) holds the legs there (without it the two legs and the torso form a parallelogram
    that only a hip torque keeps upright).

    Parameters
    ----------
    robot : RobotParameters, optional
        The robot (default: Scout II).
    model : {"II", "I", "ideal"}
        The transmission variant the state is for (the state is the same for all three:
        with no hip torque the belt is undeflected).
    controller : ControllerParameters, optional
        The controller that will hold the robot (default: Table I): each leg's compression
        must exceed its touchdown threshold, so the controller reads the leg as in stance.
    x : float
        Horizontal position of the COM [m].

    Returns
    -------
    HybridState
        For equal legs with the COM midway: pitch 0, COM height l0 - compression [m] (the
        hips are at the COM's height), toe anchors at x -/+ d/2 (half the hip spacing).

    Raises
    ------
    ValueError
        If the model has no actuators ("passive": nothing holds the legs), or the legs are
        too soft (compressed to l <= 0) or too stiff (compression below the touchdown
        threshold) to stand in the controller's stance state; the message names the field.
    """
    robot = robot if robot is not None else RobotParameters()
    ctrl = controller if controller is not None else ControllerParameters()
    if model not in ("II", "I", "ideal"):
        raise ValueError(
            f"model = {model!r} is not allowed for a standing start: must be "
            "'ideal', 'I' or 'II' (the passive model has no hip actuator to "
            "hold its legs)"
        )
    if not (isinstance(x, (int, float)) and math.isfinite(x)):
        raise ValueError(f"x = {x!r} m is not allowed: must be a finite number")
    comps = standing_leg_compressions(robot)
    lengths = []
    for leg, comp in enumerate(comps):
        l0 = robot.per_leg("leg_rest_length")[leg]
        which = "" if not robot.legs_differ else f" ({L.LEG_NAMES[leg]} leg)"
        if not comp < l0:
            raise ValueError(
                f"robot.leg_stiffness = {robot.per_leg('leg_stiffness')[leg]} N/m"
                f"{which} is not allowed for a standing start: the leg would be "
                f"compressed by {comp:.3g} m, more than its rest length "
                f"l0 = {l0} m"
            )
        if not comp > ctrl.touchdown_compression:
            raise ValueError(
                f"controller.touchdown_compression = {ctrl.touchdown_compression} "
                "m is not allowed for a standing start: the standing legs are "
                f"compressed by {comp:.4g} m only{which}, so the controller "
                "would read them as in flight; it must be below that"
            )
        lengths.append(l0 - comp)
    hb, hf = robot.hip_offset(0), robot.hip_offset(1)
    theta = math.asin((lengths[1] - lengths[0]) / (hf - hb))
    s = np.zeros(L.NS)
    s[L.IX] = x
    s[L.IY] = lengths[0] - hb * math.sin(theta)
    s[L.ITH] = theta
    for leg in range(2):
        s[L.IPHB + leg] = s[L.IALB + leg] = 0.0 - theta  # vertical legs (0.0, not -0.0)
        s[L.IL_B + leg] = lengths[leg]
    return HybridState(
        state=tuple(s),
        leg_states=(L.LS_BRAKE, L.LS_BRAKE),
        contact_modes=(L.STICK, L.STICK),
        motor_modes=(L.STUCK, L.STUCK),
        toe_anchors=(x + hb * math.cos(theta), x + hf * math.cos(theta)),
    )
