"""The Scout II bounding controller (paper Sec. II, Fig. 3-4, eqs. 2-5, Table I; SPEC.md 6).

Per virtual leg, no torso feedback, sampled at 1 kHz with zero-order hold. Sensors: hip
angle and rate relative to the torso (the motor-side angle alpha in Model II by default)
and leg length. Leg states and transitions:

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
class :class:`BoundingController` is the same law for users who want to subclass it, and
documents the interface a user-supplied controller must have.
"""

from __future__ import annotations

import numpy as np

from ..jit import kernel
from ..model.layout import (
    IALB, IL_B, IPHB, LS_BRAKE, LS_FLIGHT, LS_RETRACTION, NQ, P_ETA, P_IMAX, P_KT, P_KW,
    P_L0, P_N, P_RA, P_VB,
)
from ..model.packing import robot_array
from ..parameters import ControllerParameters

# controller parameter array layout
(C_TD_B, C_TD_F, C_SW_B, C_SW_F, C_KPF_B, C_KDF_B, C_KPF_F, C_KDF_F, C_KPB_B, C_KDB_B,
 C_KPB_F, C_KDB_F, C_TD_COMP, C_LO_COMP, C_SENSE_ALPHA, C_ENABLED) = range(16)
NC = 16


#: ControllerParameters field -> slot of the compiled controller's array, for the fields a
#: run may change while it runs (a schedule of set-points, e.g. a bench rig's steps)
SCHEDULABLE = {
    "touchdown_angle_back": C_TD_B, "touchdown_angle_front": C_TD_F,
    "sweep_limit_back": C_SW_B, "sweep_limit_front": C_SW_F,
}


def controller_array(c: ControllerParameters | None) -> np.ndarray:
    """Pack ControllerParameters into the compiled controller's array (None = disabled)."""
    a = np.zeros(NC)
    if c is None:
        return a
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
    a[C_ENABLED] = 1.0
    return a


@kernel
def retraction_torque(rate, P):
    """Stance-retraction command, eqs. (2)-(5) at the leg, per physical leg [N m].

    rate: hip angular rate relative to the torso [rad/s]."""
    N = P[P_N]
    eta = P[P_ETA]
    kt = P[P_KT]
    tau_max = N * eta * kt * P[P_VB] / P[P_RA]
    slope = -N * N * eta * kt * P[P_KW] / P[P_RA]
    tau = -tau_max + slope * rate
    lim = N * eta * kt * P[P_IMAX]
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
def sensed(s, C, leg):
    """Sensor readings (angle [rad], rate [rad/s], leg length [m]) of one leg."""
    if C[C_SENSE_ALPHA] > 0.5:
        return s[IALB + leg], s[NQ + IALB + leg], s[IL_B + leg]
    return s[IPHB + leg], s[NQ + IPHB + leg], s[IL_B + leg]


@kernel
def bounding_step(s, P, C, ls, cmd, transitions):
    """One controller sample: update leg states ``ls`` and hold commands ``cmd``.

    transitions[leg] is set to a bit mask of what happened this sample (1 touchdown
    detected, 2 sweep limit passed, 4 lift-off detected)."""
    if C[C_ENABLED] < 0.5:
        cmd[0] = 0.0
        cmd[1] = 0.0
        transitions[0] = 0
        transitions[1] = 0
        return
    l0 = P[P_L0]
    for leg in range(2):
        ang, rate, ll = sensed(s, C, leg)
        comp = l0 - ll
        sweep = C[C_SW_B + leg]
        tr = 0
        st = ls[leg]
        if st == LS_FLIGHT:
            if comp > C[C_TD_COMP]:
                st = LS_RETRACTION
                tr |= 1
        else:
            if comp < C[C_LO_COMP]:
                st = LS_FLIGHT
                tr |= 4
        if st == LS_RETRACTION and ang < sweep:
            st = LS_BRAKE
            tr |= 2
        ls[leg] = st
        transitions[leg] = tr
        if st == LS_FLIGHT:
            cmd[leg] = C[C_KPF_B + 2 * leg] * (C[C_TD_B + leg] - ang) - C[C_KDF_B + 2 * leg] * rate
        elif st == LS_RETRACTION:
            cmd[leg] = retraction_torque(rate, P)
        else:
            cmd[leg] = C[C_KPB_B + 2 * leg] * (sweep - ang) - C[C_KDB_B + 2 * leg] * rate


class BoundingController:
    """Python form of the Table I bounding controller, and the controller interface.

    A user controller is any object with

    * ``reset(robot, initial_sensors)`` (optional), called once before the run, and
    * ``command(t, sensors) -> (tau_back, tau_front)``: hip torque per physical leg at the
      leg [N m], held for one control period. ``sensors`` is a :class:`Sensors` tuple with
      ``hip_angle``, ``hip_rate``, ``leg_length`` (each a length-2 array, back then front,
      SI units) - the same readings the built-in controller uses.
    * optionally ``leg_states``: length-2 sequence of leg-state codes (0 flight,
      1 stance-retraction, 2 stance-brake) to be logged.

    Passing an instance of *this* class (not a subclass) to :func:`scoutsim.simulate` runs
    the compiled version of the same law; subclasses run through Python.
    """

    def __init__(self, params: ControllerParameters | None = None):
        self.params = params or ControllerParameters()
        self.leg_states = np.zeros(2, dtype=np.int64)
        self._P = None

    def reset(self, robot, initial_sensors=None):
        self._P = robot_array(robot, "I")
        self.leg_states[:] = LS_FLIGHT
        if initial_sensors is not None:
            for leg in range(2):
                comp = robot.leg_rest_length - initial_sensors.leg_length[leg]
                if comp > self.params.touchdown_compression:
                    self.leg_states[leg] = LS_RETRACTION

    def command(self, t, sensors):
        C = controller_array(self.params)
        s = np.zeros(16)
        s[IALB:IALB + 2] = sensors.hip_angle
        s[IPHB:IPHB + 2] = sensors.hip_angle
        s[NQ + IALB:NQ + IALB + 2] = sensors.hip_rate
        s[NQ + IPHB:NQ + IPHB + 2] = sensors.hip_rate
        s[IL_B:IL_B + 2] = sensors.leg_length
        cmd = np.zeros(2)
        tr = np.zeros(2, dtype=np.int64)
        bounding_step(s, self._P, C, self.leg_states, cmd, tr)
        return float(cmd[0]), float(cmd[1])


def max_retraction_torque(P) -> float:
    """tau_max of eq. (3) at the leg [N m] (for reports)."""
    return P[P_N] * P[P_ETA] * P[P_KT] * P[P_VB] / P[P_RA]

