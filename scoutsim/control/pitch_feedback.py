"""Table I bounding with torso feedback at touchdown: :class:`PitchFeedbackController`.

The paper's controller (Sec. II, Table I; :mod:`scoutsim.control.bounding`) places each
leg at a fixed touchdown angle relative to the torso and has no torso feedback. This
controller runs the same state machine and the same control actions
(:func:`~scoutsim.control.bounding.bounding_step`, not a copy of it) and corrects, at every
control sample, the flight servo's set point of each virtual leg by the IMU's pitch and
pitch rate::

    phi_td,leg = phi_td0,leg + k_theta,leg * theta + k_omega,leg * dtheta / dt

phi_td0 the Table I touchdown angle [rad], theta the torso pitch [rad] and dtheta/dt the
pitch rate [rad/s] as the IMU reads them (nose up positive; :mod:`.sensors`), k_theta
[rad/rad] and k_omega [s] the gains (``ControllerParameters.pitch_gain_*`` and
``pitch_rate_gain_*``). Only the flight servo reads the set point, so the correction acts
on where the toe lands; stance-retraction and stance-brake are Table I's.

The law is foot placement in the sense of Raibert (Legged Robots That Balance, MIT Press,
1986): a running machine's state is corrected by where the foot is put down for the next
stance, from the body's state sampled in flight. Raibert's one-legged machines controlled
body attitude with the hip torque in stance; Scout II's stance torque is the motor's
torque-speed line (eqs. 2-5), so here the touchdown angle carries the attitude correction
as well. The signs and gains are measured, not taken from a publication: how they follow
from single stances of the robot and what they do is in docs/model.md ("Torso feedback").

Compiled: :class:`PitchFeedbackController` is a
:class:`~scoutsim.control.compiled.CompiledController` whose parameter array is the Table I
controller array (:func:`~scoutsim.control.bounding.controller_array`, slots ``C_*``)
followed by the four gains (slots :data:`P_PITCH_GAIN_B` ...). With all four gains zero it
is the Table I controller, bit for bit (the plant's trajectory; the compiled path does not
log the controller's own touchdown / sweep / lift-off detections as events).
"""

from __future__ import annotations

import functools

import numpy as np

from .._core.model import layout as L
from ..parameters import ControllerParameters, RobotParameters, validate_controller
from .bounding import C_TD_B, NC, bounding_step, controller_array
from .compiled import CompiledController, wrap_command

__all__ = [
    "PitchFeedbackController",
    "pitch_feedback_array",
    "P_PITCH_GAIN_B",
    "P_PITCH_GAIN_F",
    "P_PITCH_RATE_GAIN_B",
    "P_PITCH_RATE_GAIN_F",
    "NP",
]

# slots of the parameter array after the Table I controller array (slots 0 .. NC - 1)
P_PITCH_GAIN_B = NC  # k_theta, back virtual leg [rad/rad]
P_PITCH_GAIN_F = NC + 1  # k_theta, front virtual leg [rad/rad]
P_PITCH_RATE_GAIN_B = NC + 2  # k_omega, back virtual leg [s]
P_PITCH_RATE_GAIN_F = NC + 3  # k_omega, front virtual leg [s]
NP = NC + 4


def pitch_feedback_array(
    params: ControllerParameters, robot: RobotParameters | None = None
) -> np.ndarray:
    """The parameter array of the compiled controller: the Table I array of ``params`` and
    ``robot`` (:func:`~scoutsim.control.bounding.controller_array`; default Scout II) and
    the four torso-feedback gains (SI)."""
    a = np.zeros(NP)
    a[:NC] = controller_array(params, robot)
    a[P_PITCH_GAIN_B] = params.pitch_gain_back
    a[P_PITCH_GAIN_F] = params.pitch_gain_front
    a[P_PITCH_RATE_GAIN_B] = params.pitch_rate_gain_back
    a[P_PITCH_RATE_GAIN_F] = params.pitch_rate_gain_front
    return a


def pitch_feedback_command(t, y, params, state, torque, leg_states):
    """One sample of the law (see the module docstring): Table I with the touchdown
    angles corrected by the IMU's pitch ``y[SN_PITCH]`` [rad] and pitch rate
    ``y[SN_PITCH_RATE]`` [rad/s]. Writes the hip torques per physical leg [N m] and the
    leg states; returns 0."""
    C = params[:NC].copy()
    pitch = y[L.SN_PITCH]
    rate = y[L.SN_PITCH_RATE]
    for leg in range(2):
        C[C_TD_B + leg] = (
            params[C_TD_B + leg]
            + params[P_PITCH_GAIN_B + leg] * pitch
            + params[P_PITCH_RATE_GAIN_B + leg] * rate
        )
    transitions = np.zeros(2, dtype=np.int64)
    bounding_step(y, C, leg_states, torque, transitions)
    return 0


@functools.lru_cache(maxsize=1)
def _compiled_command():
    """The law's C callback, compiled once per process (every controller shares it; each
    has its own parameters)."""
    return wrap_command(pitch_feedback_command)


class PitchFeedbackController(CompiledController):
    """Table I bounding with the touchdown angles corrected by torso pitch and pitch rate
    (see the module docstring), compiled into the simulator's loop.

    Parameters
    ----------
    params : ControllerParameters, optional
        Table I and the torso-feedback gains ``pitch_gain_back`` / ``_front`` [rad/rad]
        and ``pitch_rate_gain_back`` / ``_front`` [s] (default: the robot file's
        ``[controller]``, scoutsim/data/scout2.toml).

    Attributes
    ----------
    controller_parameters : the ControllerParameters it runs (a run's start places the
        legs at their Table I touchdown angles and the hip encoders read the side they
        say, as for the Table I controller).
    params : its parameter array packed with Scout II's constants; a run packs the run's
        robot's (:meth:`params_for`).

    Picklable: a copy is rebuilt from ``params`` (its compiled function is compiled once
    per process), so it can go to worker processes.
    """

    def __init__(self, params: ControllerParameters | None = None):
        params = validate_controller(params if params is not None else ControllerParameters())
        cfunc = _compiled_command()
        self.controller_parameters = params
        self.command_function = pitch_feedback_command
        self.params = pitch_feedback_array(params)
        self.initial_state = np.zeros(0)
        self.control_period = params.control_period
        self.name = "PitchFeedbackController"
        self._cfunc = cfunc
        self.compile_time_s = 0.0
        self.address = int(cfunc.address)
        self.leg_states = np.zeros(2, dtype=np.int64)

    def params_for(self, robot: RobotParameters) -> np.ndarray:
        """The parameter array for a run of ``robot`` (its leg rest length and motor
        constants, as the Table I controller packs them)."""
        assert self.controller_parameters is not None
        return pitch_feedback_array(self.controller_parameters, robot)

    def __reduce__(self):
        return (type(self), (self.controller_parameters,))

    def __repr__(self):
        c = self.controller_parameters
        return (
            f"PitchFeedbackController(k_theta = ({c.pitch_gain_back:g}, "
            f"{c.pitch_gain_front:g}), k_omega = ({c.pitch_rate_gain_back:g}, "
            f"{c.pitch_rate_gain_front:g}) s (back, front))"
        )
