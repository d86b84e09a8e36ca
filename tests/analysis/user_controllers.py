"""A user's compiled controller with a state of its own, for the orbit tests: Table I with
torso feedback on a low-passed pitch rate."""

import numba

from scoutsim.control.compiled import CompiledController
from scoutsim.control.pitch_feedback import pitch_feedback_array, pitch_feedback_command
from scoutsim.control.sensors import PITCH_RATE
from scoutsim.parameters import ControllerParameters

_pf = numba.njit(pitch_feedback_command)


def filtered_pitch_feedback(t, y, params, state, torque, leg_states):
    """Table I with torso feedback, the pitch rate low-passed (state[0], a first-order
    filter with a 10-sample time constant): a compiled controller with a state of its own."""
    state[0] += 0.1 * (y[PITCH_RATE] - state[0])
    yf = y.copy()
    yf[PITCH_RATE] = state[0]
    return _pf(t, yf, params, state, torque, leg_states)


def filtered():
    """A fresh CompiledController of :func:`filtered_pitch_feedback` (its state at 0)."""
    return CompiledController(
        filtered_pitch_feedback,
        params=pitch_feedback_array(ControllerParameters()),
        state=[0.0],
        name="filtered_pitch_feedback",
    )
