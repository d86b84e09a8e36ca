"""PitchFeedbackController (scoutsim.control.pitch_feedback): Table I with the touchdown
angles corrected by the IMU's pitch and pitch rate. What the correction does to the robot
is checked on simulations: which way a falling nose moves the front leg and what the front
stance then does to the pitch; that zero gains are the Table I controller bit for bit; that
level starts at zero pitch rate bound; that the gains load from a robot file with units."""

from __future__ import annotations

import csv
import json
import math
import pickle

import numpy as np
import pytest

import scoutsim
from scoutsim import InitialState
from scoutsim._core.model import layout as L
from scoutsim.cli import main
from scoutsim.control import PitchFeedbackController
from scoutsim.parameters import ControllerParameters, ParameterError, load_controller

MODELS = ("ideal", "I", "II")
#: the controller's detections of touchdown, sweep limit and lift-off: logged as events by
#: the built-in Table I law only (the plant's own events are the same for both)
CONTROLLER_EVENTS = [k for k, name in L.EVENT_KIND_NAMES.items() if name.startswith("controller_")]
#: a gain setting's rate gain [s] that is far from zero, of the packaged sign
RATE_GAIN = ControllerParameters().pitch_rate_gain_front


def _feedback(**gains) -> PitchFeedbackController:
    return PitchFeedbackController(ControllerParameters().replace(**gains))


def _plant_events(result) -> np.ndarray:
    return result.events[~np.isin(result.events[:, 1], CONTROLLER_EVENTS)]


def _level_start(speed: float, height: float = 0.33) -> InitialState:
    """Released in flight, torso level, no pitch rate (legs at their touchdown angles)."""
    return InitialState(dx=speed, y=height, theta=0.0, dtheta=0.0)


# -- the sign of the correction, against the robot's mechanics ----------------------------


def _before_front_touchdown(model: str):
    """A flight state of the Table I cycle 30 ms before a front touchdown (the nose is
    falling then: the back legs have pushed off)."""
    r = scoutsim.simulate(None, None, None, 5.0, model=model)
    td = r.event_times("touchdown", "front")
    k = int(np.searchsorted(r.t, td[td > 4.0][0] - 0.03))
    return r.hybrid_state(k), r.pitch_rate[k]


@pytest.mark.parametrize("model", ["I", "II"])
def test_falling_nose_places_the_front_leg_further_ahead_and_its_stance_raises_the_nose(model):
    """With the nose falling in flight, the front leg's rate gain (the packaged one, on the
    front leg alone) lands the front toe further ahead of the hip than Table I does, and
    that front stance leaves the torso pitching more nose-up at the front lift-off: the
    correction's sign is the one that recovers a falling nose."""
    start, rate = _before_front_touchdown(model)
    assert rate < math.radians(-50.0), "the nose falls before the front touchdown"
    runs = {}
    for name, ctrl in (("table_i", None), ("feedback", _feedback(pitch_rate_gain_front=RATE_GAIN))):
        r = scoutsim.simulate(None, ctrl, start, 0.4, model=model)
        t_td = r.event_times("touchdown", "front")[0]
        lo = r.event_times("liftoff", "front")
        t_lo = lo[lo > t_td][0]
        i_td, i_lo = np.searchsorted(r.t, t_td), np.searchsorted(r.t, t_lo)
        runs[name] = (r.leg_angle("front")[i_td], r.pitch_rate[i_lo])
    (phi_table, rate_table), (phi_fb, rate_fb) = runs["table_i"], runs["feedback"]
    assert phi_fb > phi_table + math.radians(2.0), "the toe lands further ahead"
    assert rate_fb > rate_table + math.radians(10.0), "the front stance raises the nose more"


def test_the_command_moves_the_flight_set_points_forward_when_the_nose_falls():
    """In flight, a nose-down pitch rate makes both flight servos push the legs forward
    (positive torque: toe ahead) harder than at zero pitch rate, by kp * k_omega * rate."""
    c = PitchFeedbackController()
    p = c.controller_parameters
    still = dict(hip_angle=(0.2, 0.2), hip_rate=(0.0, 0.0), leg_length=(0.323, 0.323), pitch=0.0)
    level = c.command(0.0, scoutsim.Sensors(**still, pitch_rate=0.0))
    falling = PitchFeedbackController().command(0.0, scoutsim.Sensors(**still, pitch_rate=-2.0))
    assert falling[0] - level[0] == pytest.approx(
        p.flight_kp_back * p.pitch_rate_gain_back * -2.0, rel=1e-12
    )
    assert falling[1] - level[1] == pytest.approx(
        p.flight_kp_front * p.pitch_rate_gain_front * -2.0, rel=1e-12
    )
    assert falling[0] > level[0] and falling[1] > level[1]


# -- zero gains: the Table I controller --------------------------------------------------


@pytest.mark.parametrize("model", MODELS)
def test_zero_gains_reproduce_table_i_bit_for_bit(model):
    """With every feedback gain zero the plant's run is the Table I controller's, bit for
    bit, also with Table I values that are not the defaults (the legs start at their
    touchdown angles; Model II's encoders read the leg side when told so)."""
    table = ControllerParameters().replace(
        touchdown_angle_back=math.radians(17.0),
        touchdown_angle_front=math.radians(23.0),
        sense_motor_angle=(model != "II"),
        pitch_gain_back=0.0,
        pitch_gain_front=0.0,
        pitch_rate_gain_back=0.0,
        pitch_rate_gain_front=0.0,
    )
    for start in (InitialState(), _level_start(1.0, 0.36)):
        a = scoutsim.simulate(None, table, start, 2.0, model=model)
        b = scoutsim.simulate(None, PitchFeedbackController(table), start, 2.0, model=model)
        assert a.outcome == b.outcome
        for name in ("t", "state", "aux", "modes"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), name
        assert np.array_equal(_plant_events(a), _plant_events(b), equal_nan=True)
        assert b.provenance["controller"]["touchdown_angle_back"] == table.touchdown_angle_back


def test_table_i_ignores_the_feedback_gains():
    """The Table I controller runs the same with and without feedback gains set."""
    gains = ControllerParameters().replace(
        pitch_gain_back=0.7,
        pitch_gain_front=-0.4,
        pitch_rate_gain_back=0.03,
        pitch_rate_gain_front=-0.02,
    )
    zero = gains.replace(
        pitch_gain_back=0.0,
        pitch_gain_front=0.0,
        pitch_rate_gain_back=0.0,
        pitch_rate_gain_front=0.0,
    )
    a = scoutsim.simulate(None, gains, None, 1.0, model="I")
    b = scoutsim.simulate(None, zero, None, 1.0, model="I")
    assert np.array_equal(a.state, b.state) and np.array_equal(a.events, b.events, equal_nan=True)


# -- level starts ------------------------------------------------------------------------


@pytest.mark.parametrize("model", MODELS)
def test_level_starts_at_zero_pitch_rate_bound_with_pitch_feedback(model):
    """Level starts without pitch motion at 0.4-1.2 m/s and both grid heights reach steady
    bounding (>= 7 steady strides after the transient, 10 s runs); with Table I the one at
    1.2 m/s, 0.33 m falls (the failure the feedback removes)."""
    c = PitchFeedbackController()
    for speed in (0.4, 0.8, 1.2):
        for height in (0.33, 0.38):
            r = scoutsim.simulate(None, c, _level_start(speed, height), 10.0, model=model)
            g = r.gait()
            assert g.is_steady_bounding(), (speed, height, r.outcome, g.n_steady_strides)
    table = scoutsim.simulate(None, None, _level_start(1.2), 10.0, model=model)
    assert table.outcome == "fell"


@pytest.mark.parametrize("model", MODELS)
def test_rate_gains_of_the_other_sign_do_not_recover_a_level_start(model):
    """The sign matters: with the rate gains' signs flipped, the level start at 1.2 m/s
    does not reach steady bounding."""
    flipped = _feedback(pitch_rate_gain_back=-RATE_GAIN, pitch_rate_gain_front=-RATE_GAIN)
    r = scoutsim.simulate(None, flipped, _level_start(1.2), 10.0, model=model)
    assert not r.gait().is_steady_bounding()


# -- parameters ----------------------------------------------------------------------------


def test_gains_load_from_a_robot_file_with_units(tmp_path):
    f = tmp_path / "robot.toml"
    f.write_text(
        "[controller]\n"
        'pitch_gain_back = { value = 0.5, unit = "deg/deg" }\n'
        'pitch_gain_front = { value = -0.25, unit = "rad/rad" }\n'
        'pitch_rate_gain_back = { value = -0.04, unit = "deg/(deg/s)" }\n'
        "pitch_rate_gain_front = -0.06\n"
    )
    c = load_controller(f)
    assert (c.pitch_gain_back, c.pitch_gain_front) == (0.5, -0.25)
    assert (c.pitch_rate_gain_back, c.pitch_rate_gain_front) == (-0.04, -0.06)
    ctrl = PitchFeedbackController(c)
    assert ctrl.controller_parameters is c


@pytest.mark.parametrize(
    "entry, words",
    [
        (
            'pitch_rate_gain_back = { value = 2.0, unit = "deg/(deg/s)" }',
            ["controller.pitch_rate_gain_back", "2.0 deg/(deg/s)", "[-0.45, 0.45]"],
        ),
        (
            'pitch_gain_front = { value = 12.0, unit = "deg/deg" }',
            ["controller.pitch_gain_front", "12.0", "[-9, 9]"],
        ),
        (
            'pitch_rate_gain_front = { value = 0.05, unit = "deg/s" }',
            ["controller.pitch_rate_gain_front", "deg/s", "angular rate unit"],
        ),
        ('pitch_gain_back = "large"', ["controller.pitch_gain_back", "wrong type"]),
        ("pitch_gain_back = nan", ["controller.pitch_gain_back", "nan"]),
    ],
)
def test_bad_gains_are_refused_naming_the_field(tmp_path, entry, words):
    f = tmp_path / "robot.toml"
    f.write_text(f"[controller]\n{entry}\n")
    with pytest.raises(ParameterError) as err:
        load_controller(f)
    for w in words:
        assert w in str(err.value)


# -- parallel workers and the command line ---------------------------------------------------


def test_pickled_controller_is_rebuilt_with_its_parameters_and_runs_the_same():
    c = _feedback(pitch_gain_back=0.3, pitch_rate_gain_front=-0.04)
    d = pickle.loads(pickle.dumps(c))
    assert d.controller_parameters == c.controller_parameters
    assert np.array_equal(d.params, c.params)
    a = scoutsim.simulate(None, c, _level_start(0.8), 1.0, model="I")
    b = scoutsim.simulate(None, d, _level_start(0.8), 1.0, model="I")
    assert np.array_equal(a.state, b.state)


def test_cli_basin_and_run_take_the_controller(tmp_path):
    """``scoutsim basin --controller pitch-feedback`` in worker processes gives the rows
    of one process, and its level start bounds; ``scoutsim run --controller`` runs it and
    refuses it on the passive model."""
    args = [
        "basin",
        "--controller",
        "pitch-feedback",
        "--model",
        "I",
        "--speeds",
        "0.8",
        "--pitch-rates",
        "0",
        "--heights",
        "0.33,0.38",
        "--floors",
        "1.0",
        "--no-progress",
        "--no-plots",
    ]
    assert main(args + ["--out", str(tmp_path / "a"), "--workers", "2"]) == 0
    assert main(args + ["--out", str(tmp_path / "b"), "--workers", "1"]) == 0
    rows = []
    for d in ("a", "b"):
        with open(tmp_path / d / "basin.csv", newline="") as fh:
            rows.append(list(csv.DictReader(fh)))
    assert rows[0] == rows[1] and len(rows[0]) == 2
    assert all(r["steady_bounding"] == "True" for r in rows[0])
    summary = json.loads((tmp_path / "a" / "basin.json").read_text())
    assert summary["controller"] == "pitch-feedback"
    assert (
        main(
            [
                "run",
                "--controller",
                "pitch-feedback",
                "--model",
                "I",
                "--duration",
                "0.5",
                "--no-progress",
                "--no-plots",
                "--out",
                str(tmp_path / "run"),
            ]
        )
        == 0
    )
    back = scoutsim.SimulationResult.load(tmp_path / "run")
    assert back.provenance["controller_kind"] == "PitchFeedbackController"
    assert (
        main(
            [
                "run",
                "--controller",
                "pitch-feedback",
                "--model",
                "passive",
                "--duration",
                "0.5",
                "--no-progress",
                "--out",
                str(tmp_path / "p"),
            ]
        )
        == 2
    )
