"""Tuning (scoutsim.analysis.tune): CMA-ES finds a known optimum, the tuned parameters
give the target speed in an independent run, a tuning reached in two calls or resumed
after an interruption equals one call, Dask = local processes, controller files round
trip, a CompiledController's parameter array is tuned, bad parameters are named."""

import importlib.util
import json
import math
import pathlib

import numpy as np
import pytest

pytest.importorskip("cmaes")

import scoutsim  # noqa: E402
from scoutsim.analysis import tune as T  # noqa: E402
from scoutsim.analysis import tune_evaluation as E  # noqa: E402
from scoutsim.analysis.controller_file import read_controller_file, write_controller_file  # noqa: E402
from scoutsim.control.pitch_feedback import PitchFeedbackController  # noqa: E402
from scoutsim.parameters import ControllerParameters, ParameterError  # noqa: E402

ANGLES = ["controller.touchdown_angle_front_deg=18:26", "controller.touchdown_angle_back_deg=16:24"]


def _table(res):
    return json.dumps(res.rows, sort_keys=True)


def test_cma_es_finds_the_minimum_of_a_known_bowl(monkeypatch):
    """The plumbing (unit cube, bounds, ask/tell, best row) on an analytic score whose
    minimum is known: a bowl centred at 22.5 / 17.25 deg."""
    centre = (math.radians(22.5), math.radians(17.25))

    def bowl(task, scenario, robot, cparams, params):
        d = (cparams.touchdown_angle_front - centre[0]) ** 2 + (
            cparams.touchdown_angle_back - centre[1]
        ) ** 2
        return {
            "score": d,
            "objective": d,
            "feasible": True,
            "violations": "",
            "outcome": "completed",
        }

    monkeypatch.setattr(E, "_scenario_row", bowl)
    res = T.tune(ANGLES, target=1.3, budget=240, workers=1, seed=3)
    assert res.best["controller.touchdown_angle_front_deg"] == pytest.approx(22.5, abs=1e-3)
    assert res.best["controller.touchdown_angle_back_deg"] == pytest.approx(17.25, abs=1e-3)
    assert res.best_values["controller.touchdown_angle_front"] == pytest.approx(centre[0], abs=2e-5)
    for r in res.rows:  # every candidate inside its bounds
        assert 18 <= r["controller.touchdown_angle_front_deg"] <= 26
        assert 16 <= r["controller.touchdown_angle_back_deg"] <= 24


def test_tuned_angles_give_the_target_speed_in_an_independent_run():
    target = 1.35
    res = T.tune(ANGLES, target=target, budget=48, duration=6.0, workers=1, sigma=0.3)
    assert res.best["feasible"]
    ctrl = ControllerParameters().replace(
        touchdown_angle_front=math.radians(res.best["controller.touchdown_angle_front_deg"]),
        touchdown_angle_back=math.radians(res.best["controller.touchdown_angle_back_deg"]),
    )
    s = scoutsim.simulate(None, ctrl, None, 6.0, model="II").summary()
    assert s["steady_bounding"]
    assert abs(s["mean_speed_m_s"] - target) < 0.02


def test_a_budget_reached_in_two_calls_gives_the_table_of_one(tmp_path):
    kw = dict(target=1.3, duration=3.0, workers=1, population=4, seed=7)
    one = T.tune(ANGLES, budget=16, out=tmp_path / "one", **kw)
    T.tune(ANGLES, budget=8, out=tmp_path / "two", **kw)
    two = T.tune(ANGLES, budget=16, out=tmp_path / "two", **kw)
    assert two.settings["n_resumed"] == 8
    assert _table(one) == _table(two)
    assert (tmp_path / "one" / "tune.csv").read_bytes() == (
        tmp_path / "two" / "tune.csv"
    ).read_bytes()


def test_an_interrupted_generation_resumes_to_the_uninterrupted_table(tmp_path, monkeypatch):
    kw = dict(target=1.3, duration=3.0, workers=1, population=4, budget=12)
    whole = T.tune(ANGLES, out=tmp_path / "whole", **kw)
    real = T.tune_task
    calls = []

    def cut(task):  # Ctrl-C during the 7th evaluation (the middle of generation 1)
        calls.append(task["evaluation"])
        if len(calls) == 7:
            raise KeyboardInterrupt
        return real(task)

    monkeypatch.setattr(T, "tune_task", cut)
    with pytest.raises(KeyboardInterrupt):
        T.tune(ANGLES, out=tmp_path / "cut", **kw)
    kept = (tmp_path / "cut" / T.EVALUATIONS).read_text().splitlines()
    assert len(kept) == 6  # every finished evaluation is kept
    manifest = json.loads((tmp_path / "cut" / "manifest.json").read_text())
    assert manifest["status"] == "partial"
    monkeypatch.setattr(T, "tune_task", real)
    resumed = T.tune(ANGLES, out=tmp_path / "cut", **kw)
    assert resumed.settings["n_resumed"] == 6
    assert _table(resumed) == _table(whole)


def test_dask_cluster_gives_the_same_evaluations_as_local_processes(dask_client):
    kw = dict(target=1.3, duration=2.0, population=4, budget=8)
    local = T.tune(ANGLES, workers=2, **kw)
    remote = T.tune(ANGLES, scheduler=dask_client, **kw)
    assert _table(local) == _table(remote)


def test_controller_file_round_trips_bit_for_bit(tmp_path):
    c = ControllerParameters().replace(
        touchdown_angle_front=0.1 + 1e-13, pitch_rate_gain_back=-0.0731
    )
    path = write_controller_file(tmp_path / "c.toml", "pitch-feedback", c, header="a\nb")
    f = read_controller_file(path)
    assert f.law == "pitch-feedback" and f.controller == c and f.robot is None
    # a controller file is a robot file too
    assert scoutsim.load_parameters(path)[1] == c


def test_a_robot_whose_legs_differ_reads_back_from_its_controller_file(tmp_path):
    """A per-leg field's (back, front) pair is written as a pair and read back exactly."""
    robot = scoutsim.RobotParameters(
        leg_stiffness=(3520.0, 3950.0 + 1e-9), leg_rest_length=(0.323, 0.305)
    )
    c = ControllerParameters()
    path = write_controller_file(tmp_path / "c.toml", "table-i", c, robot)
    f = read_controller_file(path)
    assert f.robot == robot and f.controller == c


@pytest.mark.parametrize(
    "body, field",
    [
        ("[controller]\ntouchdown_angle_front = 0.3\n", "controller_law"),
        ('[controller_law]\nname = "raibert"\n[controller]\n', "controller_law"),
        (
            '[controller_law]\nname = "table-i"\n[controller]\ntouchdown_angle_frnt = 1\n',
            "touchdown_angle_frnt",
        ),
        ('[controller_law]\nname = "table-i"\n', "controller"),
    ],
)
def test_a_bad_controller_file_is_refused_naming_the_field(tmp_path, body, field):
    p = tmp_path / "c.toml"
    p.write_text(body)
    with pytest.raises(ParameterError, match=field):
        read_controller_file(p)


def _example_controller():
    path = pathlib.Path(__file__).resolve().parents[2] / "examples" / "compiled_controller.py"
    spec = importlib.util.spec_from_file_location("compiled_controller_example", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_a_compiled_controllers_parameter_array_is_tuned():
    ex = _example_controller()
    ctrl = ex.make_controller()
    i = ex.TD + 1  # its front touchdown angle [rad]
    name = f"controller.params[{i}]=0.30:0.45"
    res = T.tune(
        [name], controller=ctrl, target=1.3, budget=8, population=4, duration=3.0, workers=1
    )
    col = f"controller.params[{i}]"
    vals = [r[col] for r in res.rows]
    assert all(0.30 <= v <= 0.45 for v in vals)
    assert res.params[i] == res.best[col]
    assert np.array_equal(np.delete(res.params, i), np.delete(ctrl.params, i))
    # the best row is the run of the best array
    again = scoutsim.simulate(
        None,
        scoutsim.CompiledController(ex.bound_with_pitch_rate, res.params),
        None,
        3.0,
        model="II",
    )
    assert again.summary()["outcome"] == res.best["outcome"]
    assert float((again.x[-1] - again.x[0]) / again.t[-1]) == res.best["average_speed_m_s"]


@pytest.mark.parametrize(
    "text, words",
    [
        ("controller.touchdown_angle_frnt_deg", ["touchdown_angle_frnt", "did you mean"]),
        ("robot.torso_mass_deg", ["torso_mass_deg", "not an angle"]),
        ("controller.touchdown_angle_front_deg=26:18", ["LOW must be below HIGH"]),
        ("controller.touchdown_angle_front_deg=-100:20", ["allowed values", "-90"]),
        ("controller.touchdown_angle_front_deg=a:b", ["NAME=LOW:HIGH"]),
        ("controller.flight_kp_front", ["flight_kp_front", "needs a range"]),
        ("controller.params[2]=0:1", ["params[2]", "CompiledController"]),
        ("robot.legs_per_virtual_leg=1:3", ["legs_per_virtual_leg", "whole number"]),
    ],
)
def test_bad_parameter_names_and_ranges_are_named(text, words):
    with pytest.raises(ValueError) as err:
        T.parse_parameter(text)
    for w in words:
        assert w in str(err.value)


def test_a_parameter_given_twice_and_a_budget_below_one_generation_are_refused():
    with pytest.raises(ValueError, match="given twice"):
        T.tune([ANGLES[0], "controller.touchdown_angle_front=0.3:0.4"], target=1.3)
    with pytest.raises(ValueError, match="budget = 3"):
        T.tune(ANGLES, target=1.3, budget=3)
    with pytest.raises(ValueError, match="target"):
        T.tune(ANGLES)


def test_the_settings_bundles_take_the_same_keywords_as_tune():
    """tune(names, target=..., budget=...) sets the fields of TuneGoal / TuneSearch; a
    keyword that is no field is refused, naming it."""
    goal, runs, search = T.bundles(
        T.TuneGoal(objective="cot"), None, None, {"budget": 8, "models": ["I"], "min_speed": 1.0}
    )
    assert goal == T.TuneGoal(objective="cot", min_speed=1.0)
    assert runs == T.TuneRuns(models=["I"]) and search == T.TuneSearch(budget=8)
    with pytest.raises(ValueError, match="budget = 3"):
        T.tune(ANGLES, goal=T.TuneGoal(target=1.3), search=T.TuneSearch(budget=3))
    with pytest.raises(TypeError, match="budgett"):
        T.tune(ANGLES, target=1.3, budgett=8)


def test_falls_rank_behind_unsteady_runs_behind_feasible_ones(monkeypatch):
    """The score orders what CMA-ES compares: feasible < constraint broken < fell, and a
    later fall before an earlier one."""
    task = {
        "goal": {
            "objective": "speed",
            "target": 1.3,
            "aggregate": "worst",
            "max_belt_deflection": None,
            "max_current": None,
            "min_speed": None,
        },
        "duration": 4.0,
        "controller": {"kind": "table-i"},
    }
    scen = {"model": "II", "friction": 1.0, "initial_state": None}
    robot = scoutsim.RobotParameters()

    def score(front_deg, back_deg, duration=4.0):
        c = ControllerParameters().replace(
            touchdown_angle_front=math.radians(front_deg),
            touchdown_angle_back=math.radians(back_deg),
        )
        return E._scenario_row(task | {"duration": duration}, scen, robot, c, None)

    steady = score(21, 19)
    short = score(21, 19, duration=2.5)  # no steady strides yet: not steady
    fell = score(21, 23)
    assert steady["feasible"] and steady["score"] < 1
    assert not short["feasible"] and "not steady" in short["violations"]
    assert steady["score"] < short["score"] < fell["score"]
    assert fell["outcome"] == "fell" and fell["score"] > 10 * T.PENALTY


def test_an_evaluation_that_cannot_be_run_stops_the_tuning_and_keeps_the_rest(
    tmp_path, monkeypatch
):
    """A task its worker cannot run (here: raises outside tune_task's own handling, as a
    Dask worker without the package would) is never scored: the tuning stops naming it,
    the finished evaluations stay, and the same call goes on once it can run."""
    import concurrent.futures as cf

    kw = dict(target=1.3, duration=2.0, population=4, budget=8)
    whole = T.tune(ANGLES, workers=1, **kw)
    real = T.tune_task

    def broken(task):
        if task["evaluation"] == 5:
            raise RuntimeError("cannot load the task")
        return real(task)

    monkeypatch.setattr(T, "tune_task", broken)
    with (
        cf.ThreadPoolExecutor(1) as pool,
        pytest.raises(T.EvaluationNotRunError, match="evaluation 5 .*cannot load"),
    ):
        T.tune(ANGLES, scheduler=pool, out=tmp_path, **kw)
    assert len((tmp_path / T.EVALUATIONS).read_text().splitlines()) == 7
    monkeypatch.setattr(T, "tune_task", real)
    again = T.tune(ANGLES, workers=1, out=tmp_path, **kw)
    assert again.settings["n_resumed"] == 7
    assert _table(again) == _table(whole)


def test_cost_of_transport_objective_and_a_current_constraint():
    """The cot objective is the run's cost of transport (as an independent run with the
    energy accounting reports it); a current limit below the run's peak current breaks
    the constraint and costs the penalty."""
    res = T.tune(ANGLES, objective="cot", budget=4, population=4, duration=6.0, workers=1)
    b = res.best
    ctrl = ControllerParameters().replace(
        touchdown_angle_front=res.best_values["controller.touchdown_angle_front"],
        touchdown_angle_back=res.best_values["controller.touchdown_angle_back"],
    )
    r = scoutsim.simulate(None, ctrl, None, 6.0, model="II", energy=True)
    assert b["feasible"] and b["objective"] == r.summary()["cost_of_transport"]
    peak = max(float(np.max(np.abs(r.motor_current(leg)))) for leg in (0, 1))
    limited = T.tune(
        ANGLES,
        objective="cot",
        budget=4,
        population=4,
        duration=6.0,
        workers=1,
        max_current=0.9 * peak,
    )
    first = limited.rows[0]
    assert "current" in first["violations"] and not first["feasible"]
    assert first["score"] > T.PENALTY


def _stability_task(duration: float, kind: str) -> dict:
    """An evaluation task of the "stability" objective for the controller ``kind``."""
    return {
        "goal": {
            "objective": "stability",
            "target": None,
            "aggregate": "worst",
            "max_belt_deflection": None,
            "max_current": None,
            "min_speed": None,
        },
        "duration": duration,
        "controller": {"kind": kind},
    }


def test_stability_objective_is_the_spectral_radius_of_the_orbit():
    task = _stability_task(6.0, "table-i")
    scen = {"model": "II", "friction": 1.0, "initial_state": None}
    row = E._scenario_row(task, scen, scoutsim.RobotParameters(), ControllerParameters(), None)
    # the Table I bound is a stable orbit (docs/orbits.md): radius below 1
    assert row["feasible"] and 0 < row["spectral_radius"] < 1
    assert row["score"] == row["objective"] == row["spectral_radius"]


def test_stability_objective_takes_a_cycle_of_several_strides_per_stride():
    """Pitch feedback at its defaults locks into a cycle of 6 strides (docs/orbits.md):
    the objective is its map's spectral radius per stride, the 6th root."""
    from scoutsim.analysis.controlled_orbit import controlled_fixed_point

    task = _stability_task(12.0, "pitch-feedback")
    scen = {"model": "II", "friction": 1.0, "initial_state": None}
    params = ControllerParameters()
    row = E._scenario_row(task, scen, scoutsim.RobotParameters(), params, None)
    orbit = controlled_fixed_point(controller=PitchFeedbackController(params))
    assert orbit.strides > 1
    rho = float(np.max(np.abs(orbit.multipliers)))
    assert row["feasible"]
    assert row["spectral_radius"] == pytest.approx(rho ** (1 / orbit.strides), rel=1e-3)
