"""Controllers compiled into the loop (scoutsim.control.compiled) and Python controllers
called from it (scoutsim.control.dispatch): the same law gives the same run either way,
bit for bit; a compiled controller keeps its state and logs its leg states; a new
controller compiles alone (nothing of the core is compiled again); failures stop the run with
the data kept; the control period is the controller's."""

import math
import sys

import numpy as np
import pytest
from numba.core.dispatcher import Dispatcher

import scoutsim
from scoutsim import InitialState
from scoutsim._core.model import layout as L
from scoutsim.control import CompiledController, Controller, ControllerError
from scoutsim.control import sensors as S

AIR = InitialState(y=1.0, dx=0.0, dtheta=0.0)  # in the air: a short, simple run


def pitch_pd(t, y, params, state, torque, leg_states):
    """Hip servo to touchdown angles corrected by the torso's pitch (reads the IMU)."""
    for leg in range(2):
        target = params[2 + leg] + params[4] * y[S.PITCH]
        torque[leg] = params[0] * (target - y[S.HIP_ANGLE + leg]) - params[1] * y[S.HIP_RATE + leg]
    return 0


PARAMS = np.array([250.0, 5.0, 0.33, 0.37, -0.5])


class PitchPD(Controller):
    """The same law in Python."""

    def command(self, t, s):
        p = PARAMS
        return tuple(
            p[0] * (p[2 + leg] + p[4] * s.pitch - s.hip_angle[leg]) - p[1] * s.hip_rate[leg]
            for leg in range(2)
        )


@pytest.fixture(scope="module")
def compiled():
    return CompiledController(pitch_pd, params=PARAMS)


@pytest.mark.parametrize("model", ["II", "I"])
def test_a_compiled_controller_runs_the_same_law_as_python(compiled, model):
    """A controller reading pitch, hip angles and rates: compiled into the loop, or called
    from Python at every sample, the run is the same bit for bit (so the compiled
    controller sees the readings the Python one does), and the pitch term acts (without
    it the run differs)."""
    a = scoutsim.simulate(None, compiled, None, 1.0, model=model)
    b = scoutsim.simulate(None, PitchPD(), None, 1.0, model=model)
    assert a.provenance["controller_kind"] == "pitch_pd"
    assert np.array_equal(a.state, b.state) and np.array_equal(a.aux, b.aux)
    blind = CompiledController(pitch_pd, params=np.r_[PARAMS[:4], 0.0])
    c = scoutsim.simulate(None, blind, None, 1.0, model=model)
    assert not np.array_equal(a.state, c.state)


def count_and_flag(t, y, params, state, torque, leg_states):
    """Counts its samples in state[0]; the torque grows with the count; the back leg is
    logged in stance-retraction after 50 samples."""
    state[0] += 1.0
    torque[0] = -1e-3 * state[0]
    torque[1] = 0.0
    leg_states[0] = L.LS_RETRACTION if state[0] > 50.0 else L.LS_FLIGHT
    leg_states[1] = L.LS_FLIGHT
    return 0


def test_a_compiled_controller_keeps_its_state_and_logs_leg_states():
    """The state carries from sample to sample (the torque of sample k is -1e-3 (k + 1)
    N m, read back from the run's commanded torque), every run starts from the initial
    state again, and the leg states it writes are logged."""
    c = CompiledController(count_and_flag, state=[0.0])
    a = scoutsim.simulate(None, c, AIR, 0.1, model="ideal")
    k = np.arange(len(a.t))
    np.testing.assert_array_equal(a.hip_torque_commanded("back"), -1e-3 * (k + 1.0))
    assert np.array_equal(a.leg_state("back") == L.LS_RETRACTION, k + 1 > 50)
    b = scoutsim.simulate(None, c, AIR, 0.1, model="ideal")
    assert np.array_equal(a.state, b.state)


def _core_specializations() -> dict[str, int]:
    """How many compiled specializations each of the core's dispatchers holds in this
    process (a function compiled again for a new argument kind adds one)."""
    counts = {}
    for name, module in list(sys.modules.items()):
        if name.startswith("scoutsim"):
            for attr, value in vars(module).items():
                if isinstance(value, Dispatcher):
                    counts[f"{name}.{attr}"] = len(value.overloads)
    return counts


def test_a_new_compiled_controller_compiles_alone(compiled):
    """Making and running a new compiled controller compiles nothing of the core again (the
    loop calls it through its address). Counted in this process, not in the disk cache:
    other test workers may be writing into the shared cache at the same time."""
    scoutsim.simulate(None, compiled, AIR, 0.01, model="II")
    before = _core_specializations()
    assert before["scoutsim._core.loop.run"] >= 1  # the loop is loaded

    def other(t, y, params, state, torque, leg_states):
        torque[0] = 0.1 * math.sin(30.0 * t)
        torque[1] = -0.2
        return 0

    c = CompiledController(other)
    r = scoutsim.simulate(None, c, AIR, 0.05, model="II")
    assert r.outcome == "completed"
    after = _core_specializations()
    assert {k: (before.get(k), n) for k, n in after.items() if before.get(k) != n} == {}


def stops_at_30(t, y, params, state, torque, leg_states):
    torque[0] = 0.0
    torque[1] = 0.0
    if t >= 0.030 - 1e-12:
        return 7
    return 0


def nan_at_20(t, y, params, state, torque, leg_states):
    torque[0] = 0.0
    torque[1] = math.nan if t >= 0.020 - 1e-12 else 0.0
    return 0


@pytest.mark.parametrize(
    "fn, sample, shown", [(stops_at_30, 30, "returned status 7"), (nan_at_20, 20, "(0.0, nan)")]
)
def test_a_compiled_controller_that_stops_or_returns_nan(fn, sample, shown):
    """A nonzero status or a torque that is not finite stops the run with a
    ControllerError naming the controller, the sample time and what it returned; the
    error's result holds the samples before."""
    c = CompiledController(fn)
    with pytest.raises(ControllerError) as info:
        scoutsim.simulate(None, c, AIR, 0.1, model="I")
    err = info.value
    assert err.sample == sample and fn.__name__ in str(err) and shown in str(err)
    assert f"t = {sample / 1000:g} s" in str(err)
    assert err.result.outcome == "controller_error" and len(err.result.t) == sample


def test_a_function_numba_cannot_compile_is_refused_when_made():
    def uses_python_objects(t, y, params, state, torque, leg_states):
        torque[0] = len({"a": object()})
        return 0

    with pytest.raises(TypeError, match="uses_python_objects.*does not compile"):
        CompiledController(uses_python_objects)


def test_ctrl_c_in_a_python_controller_keeps_the_run():
    """A KeyboardInterrupt raised in command() at t = 0.04 s ends the run as
    "interrupted" with the samples before it (as a Ctrl-C does)."""

    class Interrupted(Controller):
        def command(self, t, s):
            if t >= 0.04 - 1e-12:
                raise KeyboardInterrupt
            return (0.0, 0.0)

    r = scoutsim.simulate(None, Interrupted(), AIR, 0.1, model="I")
    assert r.outcome == "interrupted" and len(r.t) == 40


def test_the_control_period_is_the_controllers():
    """A controller with a 2 ms period is sampled (and its run recorded) every 2 ms; a
    period out of range is refused naming the field."""

    class Slow(Controller):
        control_period = 2e-3

        def __init__(self):
            self.t = []

        def command(self, t, s):
            self.t.append(t)
            return (0.0, 0.0)

    c = Slow()
    r = scoutsim.simulate(None, c, AIR, 0.02, model="I")
    np.testing.assert_allclose(np.diff(r.t), 2e-3, rtol=1e-12)
    assert np.array_equal(np.array(c.t), r.t)
    c.control_period = -1.0
    with pytest.raises(ValueError, match="control_period"):
        scoutsim.simulate(None, c, AIR, 0.02, model="I")


def test_an_object_without_command_is_refused():
    with pytest.raises(TypeError, match=r"command\(t, sensors\)"):
        scoutsim.simulate(None, object(), AIR, 0.02)
