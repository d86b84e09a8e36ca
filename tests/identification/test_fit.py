"""Identification of the hip-unit parameters from virtual rig logs: recovery
within the stated intervals, honest interval coverage over repeated noise draws,
non-identifiable parameters flagged, bad logs rejected with a clear error."""

from __future__ import annotations

import json
import math

import pytest

from scoutsim.cli import main
from scoutsim.identification import (
    FlightSteps,
    FreeSwing,
    example_robot,
    identify,
    prepare_log,
    rig_log,
    run_rig,
)
from scoutsim.parameters import RobotParameters
from scoutsim.validation.log_format import LogError

SHORT_SWING = FreeSwing(duration=1.5)


@pytest.fixture(scope="module")
def true_robot():
    return example_robot()  # Table II x (1.5, 0.7, 1.6, 0.6, 1.3, 0.8)


@pytest.fixture(scope="module")
def swing_run(true_robot):
    return run_rig(SHORT_SWING, true_robot)


def test_fit_from_table_ii_recovers_what_a_free_swing_determines(true_robot, swing_run):
    """Free swing with the torso clamped: only the reflected inertia J_2 + N^2 J_1 enters
    the dynamics, so J_1 and J_2 separately must come out not identifiable while the
    combination, the stiction and the damping are recovered within their intervals."""
    log = rig_log(swing_run, seed=7)
    # the parameters not fitted (belt) are known; the fitted ones start from Table II
    start = RobotParameters().replace(
        belt_stiffness=true_robot.belt_stiffness, belt_damping=true_robot.belt_damping
    )
    res = identify(
        [log],
        ["drive_gear_inertia", "driven_gear_inertia", "joint_stiction", "joint_damping"],
        robot=start,
        n_starts=4,
        n_local=1,
        seed=1,
    )
    for name in ("joint_stiction", "joint_damping"):
        p = res.parameters[name]
        assert p.identifiable, (name, p.reason)
        assert p.interval[0] <= getattr(true_robot, name) <= p.interval[1], name
        assert p.interval[1] / p.interval[0] < 1.1
        assert p.start == getattr(RobotParameters(), name)  # started from Table II
    assert not res.parameters["driven_gear_inertia"].identifiable
    assert not res.parameters["drive_gear_inertia"].identifiable
    comb = res.combinations["reflected_gear_inertia"]
    N = true_robot.gear_ratio
    jr = true_robot.driven_gear_inertia + N * N * true_robot.drive_gear_inertia
    # the combination is pinned to a fraction of a per mille (one draw: within 3 of its
    # 95 % half-widths)
    half = math.log(comb["interval"][1] / comb["value"])
    assert abs(math.log(comb["value"] / jr)) < min(3 * half, 1e-3)
    assert res.residual_scale == pytest.approx(1.0, abs=0.05)
    text = res.report()
    assert "NO (" in text and "reflected_gear_inertia" in text


def test_interval_coverage_over_noise_draws_is_about_the_stated_rate(true_robot, swing_run):
    """24 noise draws of one short free-swing log, local fit from the truth (coverage is a
    property of the local interval): the 95 % intervals must cover the truth about 95 % of
    the time and the 68 % ones about 68 % (bands at roughly 2.5 binomial sd; intervals
    half as wide, or twice as wide, fail them)."""
    names = ["drive_gear_inertia", "joint_stiction", "joint_damping"]
    n_draws = 24
    hit95 = dict.fromkeys(names, 0)
    hit68 = 0
    z68 = 0.9945  # two-sided 68.0 % normal quantile
    for k in range(n_draws):
        log = rig_log(swing_run, seed=1000 + k)
        res = identify([log], names, robot=true_robot, n_starts=0, n_local=1)
        for n in names:
            p = res.parameters[n]
            t = getattr(true_robot, n)
            hit95[n] += p.interval[0] <= t <= p.interval[1]
            hit68 += abs(math.log(t) - math.log(p.value)) <= z68 * p.log_sd
    total95 = sum(hit95.values())
    n_all = n_draws * len(names)
    assert all(v >= 19 for v in hit95.values()), hit95
    assert total95 >= round(0.95 * n_all - 2.5 * math.sqrt(n_all * 0.95 * 0.05)), hit95
    lo68 = 0.68 * n_all - 2.5 * math.sqrt(n_all * 0.68 * 0.32)
    hi68 = 0.68 * n_all + 2.5 * math.sqrt(n_all * 0.68 * 0.32)
    assert lo68 <= hit68 <= hi68, (hit68, lo68, hi68)


def test_leg_that_never_moves_is_a_clear_error():
    res = run_rig(FreeSwing(release_angle_back=0.0, release_angle_front=0.0, duration=0.5))
    log = rig_log(res, seed=0)
    with pytest.raises(LogError, match="never moves") as exc:
        prepare_log(log)
    assert exc.value.column == "phi_back_rad"


def test_log_without_needed_signals_is_a_clear_error(tmp_path):
    res = run_rig(FlightSteps(duration=1.5))
    log = rig_log(res, seed=0)
    del log.columns["touchdown_cmd_front_rad"]
    path = log.save(tmp_path / "steps.csv")
    with pytest.raises(LogError, match="touchdown_cmd_front_rad") as exc:
        identify([str(path)], ["joint_stiction"], n_starts=0)
    assert exc.value.column == "touchdown_cmd_front_rad" and str(path) in str(exc.value)
    # rig metadata missing
    log2 = rig_log(run_rig(FreeSwing(duration=0.5)), seed=0)
    del log2.meta["rig_config"]
    with pytest.raises(LogError, match="rig_config"):
        prepare_log(log2)
    log2.meta.pop("rig")
    with pytest.raises(LogError, match="'rig'"):
        prepare_log(log2)
    with pytest.raises(ValueError, match="params"):
        identify([rig_log(run_rig(FreeSwing(duration=0.5)))], ["leg_mass"])


def test_cli_identify_writes_identified_json(tmp_path, capsys, swing_run):
    path = rig_log(swing_run, seed=3).save(tmp_path / "swing.csv.gz")
    argv = ["identify", str(path), "--rig", "free-swing"]
    argv += ["--params", "joint_stiction,joint_damping", "--starts", "2", "--local", "1"]
    argv += ["--no-plots"]
    assert main(argv + ["--out", str(tmp_path / "out")]) == 0
    d = json.loads((tmp_path / "out" / "identified.json").read_text())
    p = d["parameters"]["joint_stiction"]
    assert p["unit"] == "N m" and p["identifiable"] is True
    assert p["interval"][0] < p["value"] < p["interval"][1]
    out = capsys.readouterr().out
    assert "joint_stiction" in out and "true" in out
    # the default: the exact Jacobian (the replays' carried derivatives)
    assert d["jacobian_method"] == "exact" and d["jacobian_evaluations"] > 0
    assert d["jacobian_fallbacks_to_differences"] == 0
    # it reaches the optimum forward differences of the residuals reach
    assert main(argv + ["--jacobian", "fd", "--out", str(tmp_path / "fd")]) == 0
    f = json.loads((tmp_path / "fd" / "identified.json").read_text())
    assert f["jacobian_method"] == "fd" and f["jacobian_evaluations"] == 0
    # (measured: a cost lower by 1e-6, values 2e-4 and 6e-4 from the differences' fit,
    # whose intervals are +-0.8 % and +-2 %: the cost is rough with the stiction)
    assert d["cost"] <= f["cost"] * (1.0 + 1e-5)
    for name in ("joint_stiction", "joint_damping"):
        lo, hi = d["parameters"][name]["interval"]
        assert lo < f["parameters"][name]["value"] < hi
    capsys.readouterr()
    # a bad log: exit code 2 and the reason
    bad = tmp_path / "bad.csv"
    bad.write_text("t,phi_back_rad\n0,0\n0.001,0\n")
    assert main(["identify", str(bad), "--rig", "free-swing", "--out", str(tmp_path / "o2")]) == 2
    assert "missing column" in capsys.readouterr().err


def test_gearbox_idle_loss_is_identified_by_the_same_machinery(true_robot):
    """The torque-dependent efficiency's parameters are identifiable like
    the others. A free swing back-drives the gear train, so an idle loss torque brakes it
    like a Coulomb friction at the leg: fitted from zero, it is recovered within its
    interval together with the joint damping."""
    robot = true_robot.replace(gearbox_idle_loss_torque=0.3)
    log = rig_log(run_rig(SHORT_SWING, robot), seed=3)
    start = robot.replace(gearbox_idle_loss_torque=0.0, joint_damping=0.5 * robot.joint_damping)
    res = identify(
        [log],
        ["gearbox_idle_loss_torque", "joint_damping"],
        robot=start,
        n_starts=4,
        n_local=1,
        seed=1,
    )
    for name in ("gearbox_idle_loss_torque", "joint_damping"):
        p = res.parameters[name]
        assert p.identifiable, (name, p.reason)
        assert p.interval[0] <= getattr(robot, name) <= p.interval[1], name
        assert p.interval[1] / p.interval[0] < 1.1
