"""What a run did (scoutsim.analysis.behaviour), on real runs set up to do each thing: the
Table I bound of Model II (steady bounding, its speed that of the steady strides), a start
that falls (pitch past its limit; a controller of zero torque: the torso sinks onto the
floor), touchdown angles far off (the robot stands), a slippery floor (the toes slide),
legs placed behind the hips (hops in place), Model I on a mu = 0.8 floor (a steady gait of
two back-leg lift-offs per cycle), a run shorter than the transient (the only "run
longer", and running longer does bound), irregular strides (no advice).

Behaviours checked against the state itself, not the classifier's own numbers: a fall by
pitch ends at the pitch limit, a fall by contact with a corner of the torso on the floor;
a standing robot has both toes down and no lift-off over its last second; the toes' slide
from their positions agrees with the slide velocity integrated over the samples; the
summary (JSON-safe) and the `scoutsim run` table say the same sentence.
"""

import dataclasses
import json
import math

import numpy as np
import pytest

import scoutsim
from scoutsim import BoundingController, Controller, InitialState, load_robot, simulate
from scoutsim._core.model import layout as L
from scoutsim.analysis.behaviour import (
    BEHAVIOUR_KINDS,
    IN_PLACE_SPEED_M_S,
    REST_S,
    RUN_LONGER,
    SLIDE_PER_METRE,
    classify_behaviour,
    toe_slide_distance,
)
from scoutsim.cli.run import format_summary
from scoutsim.names import ContactMode
from scoutsim.parameters import load_controller


class ZeroTorque(Controller):
    """A controller that commands nothing: the legs fold under the torso's weight."""

    def command(self, t, sensors):
        return (0.0, 0.0)


class Raises(Controller):
    def command(self, t, sensors):
        if t > 0.05:
            raise RuntimeError("broken controller")
        return (0.0, 0.0)


def table_i(back_deg=None, front_deg=None):
    """The Table I controller with other touchdown angles [deg]."""
    c = load_controller()
    changes = {}
    if back_deg is not None:
        changes["touchdown_angle_back"] = math.radians(back_deg)
    if front_deg is not None:
        changes["touchdown_angle_front"] = math.radians(front_deg)
    return BoundingController(c.replace(**changes))


@pytest.fixture(scope="module")
def bound():
    return simulate(duration=4.0, model="II")


def test_the_table_i_bound_is_steady_bounding_at_its_steady_speed(bound):
    b = bound.behaviour()
    g = bound.gait()
    assert b.kind == "bounding" and b.bounding and b.advice is None
    assert g.is_steady_bounding()
    assert f"at {g.mean_speed_m_s:.2f} m/s, {g.stride_frequency_hz:.2f} Hz" in b.text
    assert b.counts["speed_m_s"] == g.mean_speed_m_s
    # the Table I bound on the default floor slides little: no mention of sliding
    assert b.counts["slide_per_metre"] < SLIDE_PER_METRE / 2 and "slid" not in b.text
    s = bound.summary()
    assert s["behaviour"] == b.text and s["behaviour_kind"] == "bounding"
    assert s["behaviour_detail"]["counts"] == b.counts
    json.dumps(s, allow_nan=False)


def test_a_fall_by_pitch_ends_at_the_pitch_limit():
    """Released with the nose 40 deg up and high: the torso rotates past 60 deg."""
    r = simulate(initial_state=InitialState(theta=math.radians(40.0), y=0.5), duration=1.0)
    b = r.behaviour()
    assert r.outcome == "fell" and b.kind == "fell"
    assert b.counts["fall_cause"] == "pitch" and "pitch passed 60 deg" in b.text
    assert b.t_s == pytest.approx(r.t_end) and f"t = {r.t_end:.2f} s" in b.text
    assert abs(math.degrees(r.pitch[-1])) == pytest.approx(60.0, abs=1e-6)


def test_a_controller_of_zero_torque_collapses_onto_the_torso():
    """No hip torque: the legs fold and a corner of the torso reaches the floor."""
    r = simulate(controller=ZeroTorque(), duration=2.0)
    b = r.behaviour()
    assert b.kind == "fell" and b.counts["fall_cause"] == "torso_contact"
    assert "the torso touched the ground" in b.text and "after 0 strides" in b.text
    robot = load_robot()
    th, y = float(r.pitch[-1]), float(r.height[-1])
    lowest = (
        y
        - 0.5 * robot.torso_length * abs(math.sin(th))
        - 0.5 * robot.torso_height * abs(math.cos(th))
    )
    assert abs(lowest) < 1e-6  # the torso's lowest corner
    assert abs(math.degrees(th)) < 59.0  # not the pitch limit


def test_touchdown_angles_far_off_stand():
    """Both legs placed straight down (0 deg instead of 19 / 21): the robot lands and
    stands, both toes on the floor and no lift-off for the last second and more."""
    r = simulate(controller=table_i(0.0, 0.0), duration=3.0)
    b = r.behaviour()
    assert b.kind == "standing" and b.text.startswith("stood") and b.advice is None
    assert b.counts["n_strides"] == 0
    k = r.t >= r.t_end - REST_S
    for leg in ("back", "front"):
        assert np.all(r.contact_mode(leg)[k] != ContactMode.FLIGHT)
        lo = r.event_times("liftoff", leg)
        assert lo.size == 0 or lo.max() <= b.t_s <= r.t_end - REST_S


def test_a_slippery_floor_slides():
    """mu = 0.1: the toes slide farther than the torso goes; the slide measured from the
    toes' positions agrees with the slide velocity integrated over the samples."""
    r = simulate(friction_coefficient=0.1, duration=3.0)
    b = r.behaviour()
    assert b.kind == "sliding" and b.text.startswith("toes slid")
    assert b.counts["slide_per_metre"] >= SLIDE_PER_METRE
    for leg in (0, 1):
        mode = r.contact_mode(leg)
        v = np.abs(r.aux[:, leg * L.NAUX_LEG + L.A_SLIP_V])
        slid = (mode[1:] == ContactMode.SLIDE) & (mode[:-1] == ContactMode.SLIDE)
        integral = float(np.sum(0.5 * (v[1:] + v[:-1])[slid] * np.diff(r.t)[slid]))
        assert toe_slide_distance(r, leg) == pytest.approx(integral, rel=0.05)


def test_legs_placed_behind_the_hips_hop_in_place():
    """Front legs placed 10 deg behind the hip, back legs 8 deg ahead, from rest: the legs
    keep lifting off, the torso stays where it is."""
    r = simulate(controller=table_i(8.0, -10.0), initial_state=InitialState(dx=0.0), duration=4.0)
    b = r.behaviour()
    assert b.kind == "hopping_in_place" and b.text.startswith("hopped in place")
    assert sum(b.counts["liftoffs"].values()) >= 10
    last = r.strides[-3:]
    span = last[-1].t_end - last[0].t_start
    x = np.interp([last[0].t_start, last[-1].t_end], r.t, r.x)
    assert abs(x[1] - x[0]) / span < IN_PLACE_SPEED_M_S


def test_model_I_on_mu_08_repeats_two_back_leg_lift_offs_per_cycle():
    """Model I on a mu = 0.8 floor settles to a gait whose back legs lift off twice per
    cycle: strides alternate, every other one equal; not a bound, and not 'run longer'."""
    r = simulate(model="I", friction_coefficient=0.8, duration=5.0)
    b = r.behaviour()
    assert b.kind == "periodic" and b.advice is None and "2 back-leg lift-offs" in b.text
    p = np.array([s.period_s for s in r.strides[-6:]])
    assert np.allclose(p[2:], p[:-2], rtol=0.01) and abs(p[0] - p[1]) > 0.5 * p.max()
    assert not r.summary()["steady_bounding"]


def test_a_run_shorter_than_the_transient_says_run_longer_and_longer_bounds(bound):
    r = simulate(duration=1.0, model="II")
    b = r.behaviour()
    assert b.kind == "too_short" and b.advice == RUN_LONGER and b.text.endswith(RUN_LONGER)
    assert "transient" in b.text
    assert bound.behaviour().kind == "bounding"  # the same start run 4 s


def test_irregular_strides_get_no_run_longer():
    """Touchdown angles of 30 deg: 4 s of strides whose periods vary by a third."""
    r = simulate(controller=table_i(30.0, 30.0), duration=4.0)
    b = r.behaviour()
    assert b.kind == "irregular" and b.advice is None and RUN_LONGER not in b.text
    p = [s.period_s for s in r.strides]
    assert "none steady" in b.text and max(p) > 1.2 * min(p)


def test_stops_say_what_stopped_them(bound):
    r = simulate(load_robot(overrides={"torso_inertia": 1.3e6}), duration=0.05, model="I")
    b = r.behaviour()
    assert r.outcome == "numerical_failure" and b.kind == "numerical_failure"
    assert "the integration failed" in b.text and "singular dynamics" in b.text
    with pytest.raises(scoutsim.ControllerError) as err:  # (with the run so far)
        simulate(controller=Raises(), duration=0.5)
    r = err.value.result
    assert r.outcome == "controller_error"
    assert r.behaviour().kind == "controller_error"
    assert r.behaviour().text.startswith(f"the controller failed at t = {r.t_end:.2f} s")
    stopped = dataclasses.replace(bound, outcome="interrupted", _cache={})
    assert stopped.behaviour().text.startswith(
        "interrupted at t = 4.00 s; until then steady bounding"
    )
    assert {b.kind, "bounding", "fell"} <= set(BEHAVIOUR_KINDS)


def test_classification_is_of_the_gait_given(bound):
    """classify_behaviour with the run's own gait is the result's behaviour; a gait whose
    transient outlasts the run has no steady stride, so no bound."""
    assert classify_behaviour(bound) == bound.behaviour()
    g = scoutsim.analysis.gait.gait_metrics(bound, transient_s=10.0)
    assert classify_behaviour(bound, g).kind == "too_short"


def test_the_run_table_prints_what_the_run_did_and_run_longer_only_as_advice(bound):
    def table(r):
        return format_summary(
            r.summary(), duration=float(r.t_end), wall_s=1.0, t_end=float(r.t_end)
        )

    text = table(bound)
    assert "what the robot did" in text and "steady bounding at" in text
    assert RUN_LONGER not in text
    fell = simulate(controller=ZeroTorque(), duration=2.0)
    text = table(fell)
    assert "fell at t =" in text and RUN_LONGER not in text
    assert "n/a (no steady stride)" in text and "averaged over the run" in text
    short = simulate(duration=1.0)
    assert RUN_LONGER in " ".join(table(short).split())
