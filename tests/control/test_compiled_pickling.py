"""A compiled controller pickles (scoutsim.control.compiled): its command function by
reference, its arrays, period, name and a subclass's own attributes, whatever the
subclass's __init__ takes; the copy is wrapped again (no second compilation in the same
process) and runs the same run, bit for bit."""

import pickle

import numpy as np

import scoutsim
from scoutsim import InitialState
from scoutsim.control import CompiledController
from scoutsim.control import sensors as S

AIR = InitialState(y=1.0, dx=0.0, dtheta=0.0)


def servo(t, y, params, state, torque, leg_states):
    """Hip servo to params[2:4] with gains params[0:2]; counts its samples in state[0]."""
    state[0] += 1.0
    for leg in range(2):
        torque[leg] = (
            params[0] * (params[2 + leg] - y[S.HIP_ANGLE + leg]) - params[1] * y[S.HIP_RATE + leg]
        )
    return 0


class Gains(CompiledController):
    """A subclass made from two gains (an __init__ of its own)."""

    def __init__(self, kp, kd):
        super().__init__(servo, params=[kp, kd, 0.3, 0.35], state=[0.0], name="gains")
        self.kp, self.kd = kp, kd


def test_a_copy_runs_the_same_run_bit_for_bit():
    c = CompiledController(
        servo, params=[250.0, 5.0, 0.33, 0.37], state=[0.0], control_period=2e-3, name="servo"
    )
    copy = pickle.loads(pickle.dumps(c))
    assert (copy.name, copy.control_period, copy.command_function) == ("servo", 2e-3, servo)
    assert copy._cfunc is c._cfunc  # wrapped again, not compiled again
    a = scoutsim.simulate(None, c, AIR, 0.1, model="II")
    b = scoutsim.simulate(None, copy, AIR, 0.1, model="II")
    assert np.array_equal(a.t, b.t) and np.array_equal(a.x, b.x)
    assert np.array_equal(a.pitch, b.pitch)


def test_a_subclass_keeps_its_attributes_without_calling_its_init_again():
    g = Gains(200.0, 4.0)
    copy = pickle.loads(pickle.dumps(g))
    assert type(copy) is Gains and (copy.kp, copy.kd) == (200.0, 4.0)
    assert np.array_equal(copy.params, g.params) and copy.address == g.address
