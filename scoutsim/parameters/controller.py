""":class:`ControllerParameters`: the bounding controller's settings (paper Table I)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from .packaged import PACKAGED, packaged_defaults
from .schema import CONTROLLER_SECTIONS
from .validation import check_controller


@dataclass(frozen=True)
@packaged_defaults(*CONTROLLER_SECTIONS)
class ControllerParameters:
    """Bounding controller settings (paper Sec. II, Table I; docs/specification.md section 6), SI units.

    Gains are per physical leg, leg side (N m/rad, N m s/rad). Angles are relative to the
    torso [rad], positive with the toe ahead of the hip.

    Constructing one (also with :meth:`replace` or ``dataclasses.replace``) checks every
    value, as :class:`~scoutsim.parameters.RobotParameters` does.

    Attributes
    ----------
    touchdown_angle_front, touchdown_angle_back : float
        Flight servo set point phi_td [rad] (Table I: 21 and 19 deg).
    sweep_limit_front, sweep_limit_back : float
        Sweep-limit angle ending stance-retraction [rad] (Table I: 0).
    flight_kp_front, flight_kd_front, flight_kp_back, flight_kd_back : float
        Flight PD gains [N m/rad], [N m s/rad] (Table I: 250, 5).
    brake_kp_front, brake_kd_front, brake_kp_back, brake_kd_back : float
        Stance-brake PD gains [N m/rad], [N m s/rad] (Table I: 300, 5).
    control_period : float
        Sample-and-hold period [s] (1 ms).
    touchdown_compression : float
        Leg compression l0 - l above which the controller declares touchdown [m] (assumed).
    liftoff_compression : float
        Leg compression below which the controller declares lift-off [m] (assumed);
        must be smaller than touchdown_compression (hysteresis).
    sense_motor_angle : bool
        Model II only: sense the motor-side angle alpha (encoder) instead of phi.
    pitch_gain_front, pitch_gain_back : float
        Torso feedback of :class:`~scoutsim.control.pitch_feedback.PitchFeedbackController`
        (not Table I; the Table I controller ignores them): change of the touchdown angle
        per unit of torso pitch, k_theta [rad/rad] (given in deg/deg).
    pitch_rate_gain_front, pitch_rate_gain_back : float
        Its change of the touchdown angle per unit of pitch rate, k_omega [rad/(rad/s)] = [s]
        (given in deg/(deg/s)).
    """

    touchdown_angle_front: float = PACKAGED
    touchdown_angle_back: float = PACKAGED
    sweep_limit_front: float = PACKAGED
    sweep_limit_back: float = PACKAGED
    flight_kp_front: float = PACKAGED
    flight_kd_front: float = PACKAGED
    flight_kp_back: float = PACKAGED
    flight_kd_back: float = PACKAGED
    brake_kp_front: float = PACKAGED
    brake_kd_front: float = PACKAGED
    brake_kp_back: float = PACKAGED
    brake_kd_back: float = PACKAGED
    control_period: float = PACKAGED
    touchdown_compression: float = PACKAGED
    liftoff_compression: float = PACKAGED
    sense_motor_angle: bool = PACKAGED
    pitch_gain_front: float = PACKAGED
    pitch_gain_back: float = PACKAGED
    pitch_rate_gain_front: float = PACKAGED
    pitch_rate_gain_back: float = PACKAGED

    def __post_init__(self):
        check_controller(self)

    def replace(self, **changes) -> ControllerParameters:
        """Return a copy with some fields changed."""
        return dataclasses.replace(self, **changes)
