"""Parameter sweeps: grid/random points, failing points, resume, Parquet, Dask = kept
executor = local."""

import json
import math

import pytest

from scoutsim.analysis.sweep import (
    SUMMARY_COLUMNS,
    grid_points,
    parameter_names,
    random_points,
    sweep,
)

GRID = {
    "controller.touchdown_angle_front": [math.radians(19), math.radians(21)],
    "controller.touchdown_angle_back": [math.radians(17), math.radians(19)],
}


def test_grid_and_random_points():
    pts = grid_points(GRID)
    assert len(pts) == 4 and pts[1]["controller.touchdown_angle_back"] == pytest.approx(
        math.radians(19)
    )
    r1 = random_points({"robot.leg_damping": (40, 70)}, 5, seed=3)
    r2 = random_points({"robot.leg_damping": (40, 70)}, 5, seed=3)
    assert r1 == r2 and all(40 <= p["robot.leg_damping"] <= 70 for p in r1)
    assert "robot.leg_stiffness" in parameter_names()


def test_unknown_parameter_is_named_with_suggestion():
    with pytest.raises(ValueError, match=r"controller.touchdown_angel_front.*did you mean"):
        grid_points({"controller.touchdown_angel_front": [0.3]})


def test_failing_point_is_recorded_and_the_sweep_goes_on(tmp_path):
    """A point whose parameters are not allowed is recorded as invalid, naming the field
    (not an error of the study: the sweep goes on)."""
    pts = [{"robot.torso_mass": 20.865}, {"robot.torso_mass": -1.0}]
    res = sweep(pts, model="I", duration=0.4, workers=1, out=tmp_path)
    assert res.rows[0]["outcome"] in ("completed", "fell") and res.rows[0]["error"] == ""
    assert (
        res.rows[1]["outcome"] == "invalid_parameters"
        and res.rows[1]["status"] == "invalid"
        and "torso_mass" in res.rows[1]["error"]
    )
    assert (tmp_path / "sweep.csv").exists()


def test_resume_does_not_recompute(tmp_path):
    pts = grid_points(GRID)
    a = sweep(pts[:2], model="II", duration=0.5, workers=1, out=tmp_path)
    lines = (tmp_path / "points.jsonl").read_text().splitlines()
    assert len(lines) == 2
    b = sweep(pts, model="II", duration=0.5, workers=1, out=tmp_path)
    assert b.settings["n_resumed"] == 2
    assert b.rows[:2] == a.rows
    assert len((tmp_path / "points.jsonl").read_text().splitlines()) == 4
    # an interrupted line at the end of the checkpoint is ignored
    with open(tmp_path / "points.jsonl", "a") as f:
        f.write('{"key": "abc", "row": {')
    c = sweep(pts, model="II", duration=0.5, workers=1, out=tmp_path)
    assert c.settings["n_resumed"] == 4 and c.rows == b.rows


def test_parquet_round_trip(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")
    res = sweep(grid_points(GRID)[:2], model="I", duration=0.3, workers=1, out=tmp_path)
    t = pq.read_table(tmp_path / "sweep.parquet").to_pydict()
    for name in list(GRID) + list(SUMMARY_COLUMNS):
        assert name in t
    assert t["controller.touchdown_angle_front"] == [
        r["controller.touchdown_angle_front"] for r in res.rows
    ]


def test_dask_cluster_gives_the_same_table_as_local(tmp_path, dask_client):
    pts = grid_points(GRID)
    local = sweep(pts, model="II", duration=0.5, workers=1)
    remote = sweep(pts, model="II", duration=0.5, scheduler=dask_client)
    assert json.dumps(local.rows, sort_keys=True) == json.dumps(remote.rows, sort_keys=True)


def test_a_kept_executor_gives_the_same_table_and_stays_open():
    import concurrent.futures as cf
    import multiprocessing

    pts = grid_points(GRID)
    local = sweep(pts, model="II", duration=0.5, workers=1)
    with cf.ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        first = sweep(pts, model="II", duration=0.5, scheduler=pool)
        # the pool is the caller's: still usable for the next sweep
        second = sweep(pts[:2], model="II", duration=0.5, scheduler=pool)
    assert json.dumps(local.rows, sort_keys=True) == json.dumps(first.rows, sort_keys=True)
    assert second.rows == first.rows[:2]


def test_map_plot(tmp_path):
    res = sweep(grid_points(GRID), model="I", duration=0.3, workers=1)
    fig = res.plot_map(
        "controller.touchdown_angle_front",
        "controller.touchdown_angle_back",
        "t_end_s",
        path=tmp_path / "map.png",
    )
    ax = fig.axes[0]
    assert "[deg]" in ax.get_xlabel() and "[deg]" in ax.get_ylabel()
    assert (tmp_path / "map.png").stat().st_size > 1000


def test_orbit_columns_give_the_stability_of_each_bounding_point(tmp_path):
    from scoutsim.analysis.sweep import ORBIT_COLUMNS

    pts = [
        {
            "controller.touchdown_angle_front": math.radians(24.0),
            "controller.touchdown_angle_back": math.radians(16.0),
        },
        {
            "controller.touchdown_angle_front": math.radians(14.0),
            "controller.touchdown_angle_back": math.radians(28.0),
        },
    ]
    res = sweep(pts, duration=6.0, workers=1, out=tmp_path, orbit=True)
    bound, fell = res.rows
    assert bound["steady_bounding"] and bound["orbit_status"] == "ok"
    assert (
        bound["orbit_residual"] < 1e-7
        or bound["orbit_residual"] <= 10 * bound["orbit_residual_noise"]
    )
    # the orbit's period is a whole number of control periods, near the run's strides
    assert bound["orbit_period_s"] * 1000 == pytest.approx(round(bound["orbit_period_s"] * 1000))
    assert bound["orbit_period_s"] / bound["orbit_strides"] == pytest.approx(
        1 / bound["stride_frequency_hz"], rel=0.02
    )
    assert bound["orbit_stable"] == (bound["orbit_spectral_radius"] < 1)
    assert not fell["steady_bounding"] and fell["orbit_status"].startswith("no orbit")
    assert set(ORBIT_COLUMNS) <= set(res.columns())


def test_an_interrupted_point_is_not_recorded_and_the_resumed_table_is_the_same(
    tmp_path, interrupt_run
):
    """Ctrl-C during a point: simulate() returns the data so far with outcome
    "interrupted"; the sweep stops there without recording that point, and a resumed
    sweep gives the table of an uninterrupted one."""
    pts = grid_points(GRID)
    full = sweep(pts, model="II", duration=0.5, workers=1, out=tmp_path / "full")
    interrupt_run(3)  # (the calls after the third run as usual)
    with pytest.raises(KeyboardInterrupt):
        sweep(pts, model="II", duration=0.5, workers=1, out=tmp_path / "cut")
    lines = (tmp_path / "cut" / "points.jsonl").read_text().splitlines()
    assert len(lines) == 2
    assert all(json.loads(x)["row"]["outcome"] != "interrupted" for x in lines)
    resumed = sweep(pts, model="II", duration=0.5, workers=1, out=tmp_path / "cut")
    assert resumed.settings["n_resumed"] == 2
    assert resumed.rows == full.rows


def test_a_range_reaching_far_from_scout_ii_is_warned_of_once_not_per_point():
    """Values far from a robot of this kind warn (ImplausibleParameterWarning), but a sweep
    says it once, for its range's end, not once per point beyond the plausible range."""
    import warnings

    from scoutsim.parameters import ImplausibleParameterWarning, plausible_range

    high = plausible_range("leg_stiffness")[1]
    pts = [{"robot.leg_stiffness": v} for v in (3000.0, 3520.0, 1.2 * high, 1.5 * high)]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sweep(pts, model="ideal", duration=0.05, workers=1)
    said = [str(w.message) for w in caught if issubclass(w.category, ImplausibleParameterWarning)]
    assert len(said) == 1, said
    assert f"{1.5 * high:.6g}" in said[0] and "leg_stiffness" in said[0]


def test_a_sweep_from_a_named_start_runs_it_and_refuses_an_unknown_name(tmp_path):
    """A sweep's base start may be named as simulate() takes it ("standing": the robot at
    rest, set going by the start-up): each point runs from it and the row says which;
    an unknown name is refused before any point runs, naming the allowed ones."""
    pts = [{"controller.touchdown_angle_back_deg": 20.0}]
    res = sweep(pts, model="ideal", duration=0.6, workers=1, out=tmp_path, initial_state="standing")
    assert res.rows[0]["status"] == "ok", res.rows[0]
    assert res.settings["initial_state"] == "standing"
    with pytest.raises(ValueError, match=r"initial_state = 'sitting'.*\['flight', 'standing'\]"):
        sweep(pts, model="ideal", duration=0.6, workers=1, initial_state="sitting")


def test_orbit_columns_find_cycles_of_several_strides(tmp_path):
    """Belt stiffness x front touchdown angle (docs/orbits.md): points whose runs lock into
    a period-doubled gait (200 N m/rad, 19 deg: 2 strides of equal length) and a cycle of
    13 strides (800 N m/rad, 19 deg) have their orbits, each a whole number of control
    periods long, stable, and its period the sum of its strides."""
    from scoutsim.analysis.sweep import sweep

    pts = [
        {"robot.belt_stiffness": kb, "controller.touchdown_angle_front_deg": 19.0}
        for kb in (200.0, 800.0)
    ]
    res = sweep(pts, duration=6.0, workers=1, out=tmp_path, orbit=True)
    doubled, long = res.rows
    for row in (doubled, long):
        assert row["steady_bounding"] and row["orbit_status"] == "ok", row["orbit_status"]
        assert row["orbit_period_s"] * 1000 == pytest.approx(round(row["orbit_period_s"] * 1000))
        assert row["orbit_stable"]
        assert row["orbit_spectral_radius_per_stride"] == pytest.approx(
            row["orbit_spectral_radius"] ** (1 / row["orbit_strides"])
        )
    assert doubled["orbit_strides"] == 2 and long["orbit_strides"] == 13
    # the strides average what the run's stride frequency says
    for row in (doubled, long):
        assert row["orbit_period_s"] / row["orbit_strides"] == pytest.approx(
            1 / row["stride_frequency_hz"], rel=0.02
        )


def test_a_pitch_feedback_sweep_sets_its_gains_per_point(tmp_path):
    """controller.<field> points with pitch feedback set the parameters it runs on: with
    its four torso-feedback gains at 0 it is the Table I law (the same run as the Table I
    sweep's point, to rounding), and with a front pitch gain it bounds differently."""
    from scoutsim.analysis.sweep import sweep
    from scoutsim.control.pitch_feedback import PitchFeedbackController

    zero = {
        "controller.pitch_gain_front": 0.0,
        "controller.pitch_gain_back": 0.0,
        "controller.pitch_rate_gain_front": 0.0,
        "controller.pitch_rate_gain_back": 0.0,
    }
    pts = [zero, zero | {"controller.pitch_gain_front": 0.3}]
    pf = sweep(
        pts, duration=3.0, workers=1, out=tmp_path / "pf", controller=PitchFeedbackController()
    )
    ti = sweep([{}], duration=3.0, workers=1, out=tmp_path / "ti")
    (off, on), (table_i,) = pf.rows, ti.rows
    assert off["status"] == on["status"] == "ok"
    assert off["average_speed_m_s"] == pytest.approx(table_i["average_speed_m_s"], rel=1e-9)
    assert abs(on["average_speed_m_s"] - off["average_speed_m_s"]) > 1e-3


from scoutsim.control.bounding import BoundingController  # noqa: E402


class _StatelessTableI(BoundingController):
    """The Table I law as a Python controller that offers no state (no get_state)."""

    def command(self, t, sensors):
        return super().command(t, sensors)


def test_an_orbit_a_controller_cannot_give_keeps_the_runs_row(tmp_path):
    """A Python controller without get_state(): the point's run stands (it bounds), and
    only its orbit columns say why there is no orbit; the point is not an error and is
    not counted as not bounding."""
    from scoutsim.analysis.sweep import sweep

    res = sweep(
        [{}], duration=6.0, workers=1, out=tmp_path, orbit=True, controller=_StatelessTableI()
    )
    (row,) = res.rows
    assert row["status"] == "ok" and row["steady_bounding"]
    assert row["orbit_status"].startswith("no orbit") and "get_state" in row["orbit_status"]
