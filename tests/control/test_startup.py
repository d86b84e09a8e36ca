"""The start-up from standing (scoutsim.control.startup, simulate(initial_state="standing")):
it reaches steady bounding in each model, hands over to the unmodified Table I controller,
and bad values are refused with errors that name the field."""

import math

import numpy as np
import pytest

import scoutsim
from scoutsim import ControllerParameters, StartupParameters
from scoutsim._core.model import layout as L

MODELS = ("ideal", "I", "II")


@pytest.fixture(scope="module")
def standing_runs():
    """A 4 s run from standing per model."""
    return {m: scoutsim.simulate(initial_state="standing", duration=4.0, model=m) for m in MODELS}


@pytest.mark.parametrize("model", MODELS)
def test_startup_from_standing_reaches_steady_bounding(standing_runs, model):
    r = standing_runs[model]
    assert r.outcome == "completed"
    # steady strides after a 1.5 s transient: the bound is established 1 s after hand-over
    g = r.gait(transient_s=1.5)
    assert g.n_steady_strides >= 7
    assert g.is_steady_bounding()
    assert g.means["mean_speed_m_s"] > 1.0


@pytest.mark.parametrize("model", MODELS)
def test_startup_stands_steps_the_back_legs_pushes_and_hands_over_after_both_lift_off(
    standing_runs, model
):
    r = standing_runs[model]
    rec = r.provenance["startup"]
    assert rec["completed"]
    step, push = rec["step_s"], rec["push_s"]
    lb, lf = rec["liftoff_s"]
    assert step == pytest.approx(StartupParameters().stand_duration)
    # standing until the step: nothing moves
    before = r.t < step
    assert np.max(np.abs(r.state[before, L.NQ : 2 * L.NQ])) < 1e-9
    # the back legs lift off (the step), land (the push begins), then the front legs lift
    # off; the hand-over is the sample after the later lift-off
    assert step < lb < push < lf < step + 0.5
    assert rec["handover_s"] == pytest.approx(lf + 1e-3)
    assert r.summary()["startup_duration_s"] == rec["handover_s"]
    assert r.leg_state("back")[np.searchsorted(r.t, lb)] == L.LS_FLIGHT
    assert r.leg_state("back")[np.searchsorted(r.t, push)] == L.LS_RETRACTION
    assert np.all(r.leg_state("front")[r.t < push] == L.LS_BRAKE)
    assert r.leg_state("front")[np.searchsorted(r.t, push) + 1] == L.LS_RETRACTION
    # the stepping back legs reach their touchdown angle (Table I: 19 deg) in flight
    flight = (r.t > lb) & (r.t < push)
    assert math.degrees(np.max(r.leg_angle("back")[flight])) == pytest.approx(19.0, abs=1.5)
    # the push moves the robot forward and pitches its nose up
    k = np.searchsorted(r.t, lf)
    assert r.forward_speed[k] > 0.0 and r.pitch_rate[k] > 0.0


def test_after_the_handover_the_controller_runs_with_its_own_parameters():
    # the rest of the run is the Table I controller from the hand-over state: resuming it
    # there with the plain controller gives the same motion (to the integration tolerance)
    r = scoutsim.simulate(initial_state="standing", duration=1.0, model="ideal")
    k = int(np.searchsorted(r.t, r.provenance["startup"]["handover_s"]))
    resumed = scoutsim.simulate(
        initial_state=r.hybrid_state(k), duration=r.t[-1] - r.t[k], model="ideal"
    )
    n = min(len(resumed.t), len(r.t) - k)
    assert np.max(np.abs(resumed.state[:n, :3] - r.state[k : k + n, :3])) < 1e-5


def test_a_custom_startup_is_used_and_recorded():
    su = StartupParameters(
        stand_duration=0.1, step_angle_back=math.radians(21.0), front_pushoff_angle=None
    )
    r = scoutsim.simulate(initial_state="standing", duration=0.6, model="I", startup=su)
    rec = r.provenance["startup"]
    assert rec["step_s"] == pytest.approx(0.1)
    assert rec["push_s"] is None and rec["completed"]  # the front legs did not push
    assert np.all(r.leg_state("front")[r.t < rec["liftoff_s"][1]] == L.LS_BRAKE)
    assert rec["parameters"]["step_angle_back"] == pytest.approx(math.radians(21.0))
    assert rec["parameters"]["step_kp"] == ControllerParameters().brake_kp_back


def test_bad_starts_are_refused_naming_the_field():
    with pytest.raises(ValueError, match="initial_state = 'sitting'"):
        scoutsim.simulate(initial_state="sitting", duration=0.01)
    with pytest.raises(ValueError, match="model = 'passive'"):
        scoutsim.simulate(initial_state="standing", duration=0.01, model="passive")
    with pytest.raises(ValueError, match="user controller"):
        scoutsim.simulate(
            controller=type("Mine", (), {"command": lambda self, t, s: (0, 0)})(),
            initial_state="standing",
            duration=0.01,
        )
    with pytest.raises(ValueError, match="startup is only allowed"):
        scoutsim.simulate(duration=0.01, startup=StartupParameters())
    with pytest.raises(TypeError, match="startup must be StartupParameters"):
        scoutsim.simulate(initial_state="standing", duration=0.01, startup={"x": 1})


@pytest.mark.parametrize(
    "field, value",
    [
        ("stand_duration", -0.1),
        ("stand_duration", math.nan),
        ("handover_timeout", 0.0),
        ("handover_timeout", 10.0),
        ("step_angle_back", math.radians(95.0)),
        ("front_pushoff_angle", math.inf),
        ("step_kp", -1.0),
        ("step_kd", "5"),
    ],
)
def test_bad_startup_parameters_are_refused_naming_the_field(field, value):
    with pytest.raises(ValueError, match=f"startup.{field} = "):
        StartupParameters(**{field: value})


def test_flight_by_name_is_the_default_start():
    a = scoutsim.simulate(initial_state="flight", duration=0.3, model="I")
    b = scoutsim.simulate(duration=0.3, model="I")
    assert np.array_equal(a.state, b.state)
    assert "startup" not in a.provenance and "startup_duration_s" not in a.summary()
