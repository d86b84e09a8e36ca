"""A run's start as the compiled loop takes it: the state vector of an
:class:`~scoutsim.state.InitialState` (checked), the default start of each model, the
mode arrays of a fresh or a resumed start, and the starts known by name ("flight",
"standing")."""

from __future__ import annotations

import math
from dataclasses import fields

import numpy as np

from .._core.model import layout as L
from .._core.model.transmission import motor_mode_from_rate
from ..control.startup import StartupParameters
from ..parameters import ControllerParameters, RobotParameters
from ..state import HybridState, InitialState, standing_state

__all__ = [
    "default_initial_state",
    "fresh_modes",
    "resumed_modes",
    "initial_state_vector",
    "named_start",
    "NAMED_STARTS",
]


def initial_state_vector(
    init: InitialState,
    robot: RobotParameters,
    ctrl: ControllerParameters | None,
    passive_angles,
    passive_world,
) -> np.ndarray:
    """The state vector (layout ``STATE_NAMES``, SI) of a start in flight ``init``, checked:
    finite values, |pitch| < 90 deg, leg lengths in (0, l0], both toes above the ground.
    Leg angles ``init`` leaves open are the touchdown angles of the Table I controller
    ``ctrl``, or (``ctrl`` None: massless legs without one) ``passive_angles`` (back,
    front) [rad], from the world vertical if ``passive_world`` else relative to the torso."""
    s = np.zeros(L.NS)
    vals = {f.name: getattr(init, f.name) for f in fields(init)}
    for name, v in vals.items():
        if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v)):
            raise ValueError(f"initial_state.{name} = {v!r} is not allowed: must be finite")
    if not (-math.pi / 2 < init.theta < math.pi / 2):
        raise ValueError(
            f"initial_state.theta = {math.degrees(init.theta):.1f} deg is not "
            "allowed: must be in (-90, 90) deg"
        )
    if ctrl is not None:
        td = (ctrl.touchdown_angle_back, ctrl.touchdown_angle_front)
    elif passive_world:
        td = (passive_angles[0] - init.theta, passive_angles[1] - init.theta)
    else:
        td = tuple(passive_angles)
    phib = td[0] if init.phi_back is None else init.phi_back
    phif = td[1] if init.phi_front is None else init.phi_front
    l0b, l0f = robot.per_leg("leg_rest_length")
    lb = l0b if init.leg_length_back is None else init.leg_length_back
    lf = l0f if init.leg_length_front is None else init.leg_length_front
    for name, v, l0 in (("leg_length_back", lb, l0b), ("leg_length_front", lf, l0f)):
        if not (0.0 < v <= l0):
            raise ValueError(f"initial_state.{name} = {v} m is not allowed: must be in (0, {l0}] m")
    s[: L.NQ] = [init.x, init.y, init.theta, phib, phif, phib, phif]
    s[L.NQ : 2 * L.NQ] = [
        init.dx,
        init.dy,
        init.dtheta,
        init.dphi_back,
        init.dphi_front,
        init.dphi_back,
        init.dphi_front,
    ]
    s[L.IL_B] = lb
    s[L.IL_F] = lf
    # both toes must start above ground (the run starts in double flight)
    for leg, name in ((0, "back"), (1, "front")):
        sL = robot.hip_offset(leg)
        g = init.theta + s[L.IPHB + leg]
        toe_y = init.y + sL * math.sin(init.theta) - s[L.IL_B + leg] * math.cos(g)
        if toe_y < 0.0:
            raise ValueError(
                f"initial_state.y = {init.y} m is not allowed: the {name} toe "
                f"starts {-toe_y * 1000:.1f} mm below the ground; the run "
                "starts in flight, raise y or change the leg angles"
            )
    return s


def default_initial_state(
    model: str = "II", robot: RobotParameters | None = None, passive_touchdown_angles=(0.0, 0.0)
) -> InitialState:
    """The documented default start of ``model`` (see :class:`~scoutsim.state.InitialState`).

    Parameters
    ----------
    model : {"II", "I", "ideal", "passive"}
        The model the start is for.
    robot : RobotParameters, optional
        The robot (default: Scout II); only the passive start depends on it (through its
        leg rest length l0).
    passive_touchdown_angles : (back, front) [rad]
        Passive model only: where its legs are placed (as for :func:`~scoutsim.simulation.simulator.simulate`).

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
    l0b, l0f = robot.per_leg("leg_rest_length")
    start = InitialState()
    drop_controlled = max(
        l0b * math.cos(ctrl.touchdown_angle_back), l0f * math.cos(ctrl.touchdown_angle_front)
    )
    drop_passive = max(l0 * math.cos(a) for l0, a in zip((l0b, l0f), passive_touchdown_angles))
    return start.replace(y=start.y - drop_controlled + drop_passive, dx=1.0)


def fresh_modes(s: np.ndarray, P: np.ndarray):
    """Mode arrays (mi, mf) of a start from state ``s`` with both toes in flight; each
    motor joint's stick/slip mode from its gear rate by the same rule as after an impact
    (:func:`~scoutsim._core.model.transmission.motor_mode_from_rate`: slipping in the direction of
    motion; at rest stuck if it has stiction, else "slipping" with zero Coulomb torque)."""
    mi = np.zeros(L.NMI, dtype=np.int64)
    mf = np.zeros(L.NMF)
    for leg in range(2):
        mi[L.MI_MOTOR_B + leg] = motor_mode_from_rate(float(s[L.NQ + L.IALB + leg]), leg, P)
        mi[L.MI_SLIDE_DIR_B + leg] = 1
    return mi, mf


def resumed_modes(init: HybridState):
    """Mode arrays (mi, mf) and controller leg states of a run resumed at ``init``."""
    mi, mf = init.mode_arrays()
    return mi, mf, np.array(init.leg_states, dtype=np.int64)


#: the starts ``simulate(initial_state=...)`` knows by name
NAMED_STARTS = ("flight", "standing")


def named_start(initial_state, startup, model, robot, cparams, user_ctrl):
    """Resolve a start given by name: (initial state or None for the default, start-up
    parameters or None). "flight": the default start; "standing": the robot at rest
    (:func:`~scoutsim.state.standing_state`) and the start-up of
    :mod:`scoutsim.control.startup`, which needs the built-in Table I controller."""
    if not isinstance(initial_state, str):
        if startup is not None:
            raise ValueError("startup is only allowed with initial_state='standing'")
        return initial_state, None
    if initial_state not in NAMED_STARTS:
        raise ValueError(
            f"initial_state = {initial_state!r} is not allowed: must be an "
            f"InitialState, a HybridState or one of {list(NAMED_STARTS)}"
        )
    if initial_state == "flight":
        if startup is not None:
            raise ValueError("startup is only allowed with initial_state='standing'")
        return None, None
    if user_ctrl is not None:
        raise ValueError(
            "initial_state = 'standing' is not allowed with a user controller "
            f"({type(user_ctrl).__name__}): the start-up runs the built-in "
            "Table I controller (pass ControllerParameters or None)"
        )
    if model == "passive" or cparams is None:
        raise ValueError(
            "initial_state = 'standing' is not allowed with model = "
            f"{model!r}: the standing robot is held and set going by the "
            "bounding controller (model 'ideal', 'I' or 'II')"
        )
    if startup is None:
        startup = StartupParameters()
    elif not isinstance(startup, StartupParameters):
        raise TypeError(f"startup must be StartupParameters, not {type(startup).__name__}")
    return standing_state(robot, model, cparams), startup
