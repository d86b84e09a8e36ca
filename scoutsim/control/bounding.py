"""The Scout II bounding controller (paper Sec. II, Fig. 3-4, eqs. 2-5, Table I;
docs/specification.md section 6).

Per virtual leg, no torso feedback, sampled at 1 kHz with zero-order hold. The controller
sees only its sensor readings (``layout.SN_*``, read by :mod:`scoutsim._core.model.sensor_readings`: hip
angle and rate relative to the torso, the motor-side angle alpha in Model II by default,
and leg length) and its own parameters (:func:`controller_array`: Table I, plus the motor
constants of eqs. 2-4 and the leg rest length, packed once from the robot); never the
plant's state or parameter array. Leg states and transitions:

* flight -> stance-retraction when the leg compression l0 - l exceeds the touchdown
  threshold;
* stance-retraction -> stance-brake when the hip angle falls below the sweep limit;
* stance-retraction / stance-brake -> flight when the compression falls below the lift-off
  threshold (hysteresis: lift-off threshold < touchdown threshold).

Control actions, torque per physical leg at the leg:

* flight: tau = kp (phi_td - phi) - kd dphi;
* stance-retraction: tau = -tau_max + A dphi, tau_max = N eta K_T V_bar / R_A,
  A = -N^2 eta K_T K_w / R_A (eqs. 2-3, leg side); a positive command is set to 0 (eq. 5),
  one below -N eta K_T i_max to that limit (eq. 4);
* stance-brake: tau = kp_b (phi_sweep - phi) - kd_b dphi.

The compiled version (:func:`bounding_step`) runs inside the integrator loop; the Python
class :class:`BoundingController` is the same law behind the controller protocol
(:mod:`scoutsim.control.protocol`), for users who want to subclass it.
"""

from __future__ import annotations

import numpy as np

from .._core.model.flags import FLAG_ON, is_set
from .._core.model.layout import (
    LS_BRAKE,
    LS_FLIGHT,
    LS_RETRACTION,
    SN_ANGLE_B,
    SN_LENGTH_B,
    SN_RATE_B,
    TR_LIFTOFF,
    TR_SWEEP,
    TR_TOUCHDOWN,
)
from .._numba.jit import kernel
from ..parameters import ControllerParameters, RobotParameters
from .protocol import Controller

# controller parameter array layout
(
    C_TD_B,
    C_TD_F,
    C_SW_B,
    C_SW_F,
    C_KPF_B,
    C_KDF_B,
    C_KPF_F,
    C_KDF_F,
    C_KPB_B,
    C_KDB_B,
    C_KPB_F,
    C_KDB_F,
    C_TD_COMP,
    C_LO_COMP,
    C_SENSE_ALPHA,
    C_ENABLED,
) = range(16)
# what the controller knows of the robot (packed once by controller_array), per virtual
# leg: two slots, back then front (C[C_X + leg])
C_L0 = 16  # leg rest length l0 [m] (compression = l0 - sensed length)
C_TAU_MAX = 18  # tau_max = N eta K_T V_bar / R_A of eq. (3), at the leg [N m]
C_SLOPE = 20  # A = -N^2 eta K_T K_w / R_A of eq. (2), at the leg [N m s/rad]
C_TAU_LIMIT = 22  # N eta K_T i_max of eq. (4), at the leg [N m]
NC = 24


#: ControllerParameters field -> slot of the compiled controller's array, for the fields a
#: run may change while it runs (a schedule of set-points, e.g. a bench rig's steps)
SCHEDULABLE = {
    "touchdown_angle_back": C_TD_B,
    "touchdown_angle_front": C_TD_F,
    "sweep_limit_back": C_SW_B,
    "sweep_limit_front": C_SW_F,
}


def retraction_constants(robot: RobotParameters) -> tuple[float, float, float]:
    """(tau_max, A, torque limit) of the stance-retraction law, eqs. (2)-(4), at the leg
    [N m, N m s/rad, N m] from the motor's constants of ``robot`` (one leg's:
    ``robot.leg("front")`` when the legs differ): tau_max = N eta K_T V / R_A,
    A = -N^2 eta K_T K_w / R_A, limit = N eta K_T i_max (the robot's torque-speed line
    and current limit, :class:`~scoutsim.parameters.RobotParameters`)."""
    return robot.stall_torque, -robot.torque_speed_slope, robot.max_leg_torque


def controller_array(
    c: ControllerParameters | None, robot: RobotParameters | None = None
) -> np.ndarray:
    """Pack ControllerParameters, and what the controller knows of ``robot`` (leg rest
    length, the motor constants of eqs. 2-4; default Scout II), into the compiled
    controller's array (``c`` None = disabled)."""
    a = np.zeros(NC)
    if c is None:
        return a
    robot = robot if robot is not None else RobotParameters()
    for leg in range(2):
        one = robot.leg(leg)
        a[C_L0 + leg] = one.leg_rest_length
        a[C_TAU_MAX + leg], a[C_SLOPE + leg], a[C_TAU_LIMIT + leg] = retraction_constants(one)
    a[C_TD_B] = c.touchdown_angle_back
    a[C_TD_F] = c.touchdown_angle_front
    a[C_SW_B] = c.sweep_limit_back
    a[C_SW_F] = c.sweep_limit_front
    a[C_KPF_B] = c.flight_kp_back
    a[C_KDF_B] = c.flight_kd_back
    a[C_KPF_F] = c.flight_kp_front
    a[C_KDF_F] = c.flight_kd_front
    a[C_KPB_B] = c.brake_kp_back
    a[C_KDB_B] = c.brake_kd_back
    a[C_KPB_F] = c.brake_kp_front
    a[C_KDB_F] = c.brake_kd_front
    a[C_TD_COMP] = c.touchdown_compression
    a[C_LO_COMP] = c.liftoff_compression
    a[C_SENSE_ALPHA] = 1.0 if c.sense_motor_angle else 0.0
    a[C_ENABLED] = FLAG_ON
    return a


@kernel
def retraction_torque(rate, leg, C):
    """Stance-retraction command of virtual leg ``leg``, eqs. (2)-(5) at the leg, per
    physical leg [N m].

    rate: hip angular rate relative to the torso [rad/s]."""
    tau = -C[C_TAU_MAX + leg] + C[C_SLOPE + leg] * rate
    lim = C[C_TAU_LIMIT + leg]
    # eq. (5) before eq. (4): read literally in the paper's order, (4) would turn a positive
    # command larger than the current limit (a leg spun backwards beyond 1.4 x the motor's
    # no-load speed) into full negative torque; the paper's footnote 2 gives (4) for
    # "excessively large torques" at small rates and (5) for a "change of sign"
    if tau >= 0.0:
        tau = 0.0
    elif tau < -lim:
        tau = -lim
    return tau


@kernel
def bounding_step(y, C, ls, cmd, transitions):
    """One controller sample from the sensor readings ``y`` (``layout.SN_*``): update leg
    states ``ls`` and hold commands ``cmd``.

    transitions[leg] is set to a bit mask of what happened this sample (``layout.TR_*``:
    touchdown detected, sweep limit passed, lift-off detected)."""
    if not is_set(C[C_ENABLED]):
        cmd[0] = 0.0
        cmd[1] = 0.0
        transitions[0] = 0
        transitions[1] = 0
        return
    for leg in range(2):
        ang = y[SN_ANGLE_B + leg]
        rate = y[SN_RATE_B + leg]
        comp = C[C_L0 + leg] - y[SN_LENGTH_B + leg]
        sweep = C[C_SW_B + leg]
        tr = 0
        st = ls[leg]
        if st == LS_FLIGHT:
            if comp > C[C_TD_COMP]:
                st = LS_RETRACTION
                tr |= TR_TOUCHDOWN
        else:
            if comp < C[C_LO_COMP]:
                st = LS_FLIGHT
                tr |= TR_LIFTOFF
        if st == LS_RETRACTION and ang < sweep:
            st = LS_BRAKE
            tr |= TR_SWEEP
        ls[leg] = st
        transitions[leg] = tr
        if st == LS_FLIGHT:
            cmd[leg] = C[C_KPF_B + 2 * leg] * (C[C_TD_B + leg] - ang) - C[C_KDF_B + 2 * leg] * rate
        elif st == LS_RETRACTION:
            cmd[leg] = retraction_torque(rate, leg, C)
        else:
            cmd[leg] = C[C_KPB_B + 2 * leg] * (sweep - ang) - C[C_KDB_B + 2 * leg] * rate


@kernel
def bounding_step_t(y, C, ls, tangents, cmd_t):
    """The derivative of the commands :func:`bounding_step` sets [N m per unit of the
    direction], along one direction with tangents ``tangents`` = (y_t, C_t) of the readings
    ``y`` and the law's parameters ``C``, in the leg states ``ls`` the sample switched to
    (held: the transitions are the sample's discrete choices). The leg length decides
    transitions only; the retraction torque's clipping (eqs. 4-5) is differentiated on the
    side the command is on."""
    y_t, C_t = tangents
    if not is_set(C[C_ENABLED]):
        cmd_t[0] = 0.0
        cmd_t[1] = 0.0
        return
    for leg in range(2):
        ang = y[SN_ANGLE_B + leg]
        rate = y[SN_RATE_B + leg]
        ang_t = y_t[SN_ANGLE_B + leg]
        rate_t = y_t[SN_RATE_B + leg]
        st = ls[leg]
        if st == LS_FLIGHT:
            kp, kd = C_KPF_B + 2 * leg, C_KDF_B + 2 * leg
            target = C_TD_B + leg
        elif st == LS_BRAKE:
            kp, kd = C_KPB_B + 2 * leg, C_KDB_B + 2 * leg
            target = C_SW_B + leg
        else:
            # (the clipping's side from the clipped value: 0 or the limit exactly)
            tau = retraction_torque(rate, leg, C)
            if tau == 0.0:
                cmd_t[leg] = 0.0
            elif tau == -C[C_TAU_LIMIT + leg]:
                cmd_t[leg] = -C_t[C_TAU_LIMIT + leg]
            else:
                cmd_t[leg] = (
                    -C_t[C_TAU_MAX + leg] + C_t[C_SLOPE + leg] * rate + C[C_SLOPE + leg] * rate_t
                )
            continue
        cmd_t[leg] = (
            C_t[kp] * (C[target] - ang)
            + C[kp] * (C_t[target] - ang_t)
            - C_t[kd] * rate
            - C[kd] * rate_t
        )


class BoundingController(Controller):
    """The Table I bounding controller behind the controller protocol
    (:mod:`scoutsim.control.protocol`).

    Passed to :func:`scoutsim.simulate`, it runs compiled (:func:`bounding_step` inside the
    loop), and so does a subclass that does not override :meth:`command`; a subclass that
    overrides it runs through Python (the same law if it calls ``super().command``).

    params : ControllerParameters (default: Table I).
    control_period : the parameters' sample-and-hold period [s] (Table I: 1 ms).
    leg_states : (2,) the leg states (0 flight, 1 stance-retraction, 2 stance-brake),
        back then front, as of the last command.
    """

    def __init__(self, params: ControllerParameters | None = None):
        self.params = params or ControllerParameters()
        self.leg_states = np.zeros(2, dtype=np.int64)
        self._C = None

    @property
    def control_period(self) -> float:  # type: ignore[override]  # (the parameters' period)
        return self.params.control_period

    def reset(self, robot, sensors=None):
        """Pack the parameters with ``robot``'s motor constants; a leg whose first reading
        is compressed beyond the touchdown threshold starts in stance-retraction."""
        self._C = controller_array(self.params, robot)
        self.leg_states[:] = LS_FLIGHT
        if sensors is not None:
            for leg in range(2):
                comp = robot.leg(leg).leg_rest_length - sensors.leg_length[leg]
                if comp > self.params.touchdown_compression:
                    self.leg_states[leg] = LS_RETRACTION

    def command(self, t, sensors):
        """Hip torques (back, front) [N m] of one sample (updates ``leg_states``)."""
        if self._C is None:
            raise RuntimeError(
                "BoundingController.command before reset(robot): the "
                "controller needs the robot's motor constants"
            )
        y = np.array(sensors.vector, dtype=float)
        cmd = np.zeros(2)
        tr = np.zeros(2, dtype=np.int64)
        bounding_step(y, self._C, self.leg_states, cmd, tr)
        return float(cmd[0]), float(cmd[1])
