"""Tests of command-line paths that tests/test_cli.py does not cover: `scoutsim rig` with
each of its options, `--version`, `identify --example` and `identify --rig flight-steps`,
`sweep --orbit`, `sweep --no-resume`, a `sweep --random` sample, `orbit --model I` and
`run --model ideal`. Each checks what the command says it does: exit code, the files it
writes and, where the command reports physics, that physics from independent formulas."""

import csv
import json
import math
import subprocess
import sys

import numpy as np
import pytest

import scoutsim
from scoutsim import ControllerParameters, HybridState, IntegratorSettings, RobotParameters
from scoutsim.cli import main
from scoutsim.model import layout as L
from scoutsim.run_directory import check_run_directory
from scoutsim.validation.logs import load_log

DT = 1e-3   # the Table I control period [s]: the rigs sample at it


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


# -----------------------------------------------------------------------------------------
# scoutsim --version
# -----------------------------------------------------------------------------------------
def test_version_option_prints_the_package_version(capsys):
    """`scoutsim --version` prints "scoutsim <scoutsim.__version__>" and exits 0, in
    process and as `python -m scoutsim`."""
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"scoutsim {scoutsim.__version__}"
    proc = subprocess.run([sys.executable, "-m", "scoutsim", "--version"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"scoutsim {scoutsim.__version__}"


# -----------------------------------------------------------------------------------------
# scoutsim rig
# -----------------------------------------------------------------------------------------
def _swing_balance(robot, toe_mass):
    """Shorted-lead creep of a free swing (docs/identification.md): gravity torque
    coefficient (m d + m_t l0) g [N m] and the viscous coefficient at the leg
    N^2 eta K_T K_w / R_A + N^2 b_J [N m s/rad]."""
    N = robot.gear_ratio
    kg = (robot.leg_mass * robot.leg_com_distance + toe_mass * robot.leg_rest_length) \
        * robot.gravity
    b = (N * N * robot.efficiency * robot.torque_constant * robot.speed_constant
         / robot.armature_resistance + N * N * robot.joint_damping)
    return kg, b


def test_rig_free_swing_with_shorted_leads_creeps_at_the_back_emf_balance(tmp_path, capsys):
    """`rig free-swing --motor short --toe-mass --release --duration --no-noise`: the log
    starts at the release angles, lasts the duration, and shows the shorted winding's
    physics: current i = -K_w N dalpha / R_A, and the leg (with the given toe mass) creeps
    where gravity balances back-EMF, joint damping and stiction,
    (m d + m_t l0) g sin(phi) = b |dphi| + N tau_s."""
    out = tmp_path / "rig"
    code = main(["rig", "free-swing", "--motor", "short", "--toe-mass", "2", "--release",
                 "60,0", "--duration", "2", "--no-noise", "--out", str(out)])
    assert code == 0
    path = out / "free-swing.csv.gz"
    assert f"free-swing rig: completed, 2001 samples; wrote {path}" in capsys.readouterr().out
    log = load_log(path)
    c = log.columns
    assert log.meta["rig"] == "free-swing" and log.meta["sensor_noise"] is None
    assert log.meta["rig_config"]["motor"] == "short"
    assert log.meta["rig_config"]["toe_mass"] == 2.0
    np.testing.assert_allclose(c["t"], np.arange(2001) * DT, atol=1e-9)
    assert c["phi_back_rad"][0] == pytest.approx(math.radians(60.0), abs=1e-6)
    # the front leg was released hanging straight down: it stays there
    assert np.max(np.abs(c["phi_front_rad"])) < 1e-9

    robot = RobotParameters()
    N = robot.gear_ratio
    k = c["t"] > 1.0                          # after the transient of the release
    phi, rate = c["phi_back_rad"][k], c["dphi_back_rad_s"][k]
    np.testing.assert_allclose(c["current_back_a"][k],
                               -robot.speed_constant * N * rate / robot.armature_resistance,
                               rtol=1e-3)
    kg, b = _swing_balance(robot, toe_mass=2.0)
    np.testing.assert_allclose(rate, -(kg * np.sin(phi) - N * robot.joint_stiction) / b,
                               rtol=0.01)


def test_rig_free_swing_open_leads_carry_no_current_and_noise_follows_the_seed(tmp_path):
    """Open leads (the default): no current flows (noise-free log: exactly 0). With the
    default sensor noise the current channel is white noise of the stated 0.05 A; the same
    --seed gives the same log, another seed another one."""
    def log(name, *extra):
        out = tmp_path / name
        assert main(["rig", "free-swing", "--duration", "0.5", "--out", str(out),
                     *extra]) == 0
        return load_log(out / "free-swing.csv.gz")

    clean = log("clean", "--no-noise")
    assert clean.meta["rig_config"]["motor"] == "open"
    for leg in ("back", "front"):
        assert np.all(clean.columns[f"current_{leg}_a"] == 0.0)
    # default release angles: back +60 deg, front -40 deg
    assert clean.columns["phi_back_rad"][0] == pytest.approx(math.radians(60.0), abs=1e-6)
    assert clean.columns["phi_front_rad"][0] == pytest.approx(math.radians(-40.0), abs=1e-6)

    a, a2, b = log("a", "--seed", "7"), log("a2", "--seed", "7"), log("b", "--seed", "8")
    assert a.meta["noise_seed"] == 7 and b.meta["noise_seed"] == 8
    for name in a.columns:
        np.testing.assert_array_equal(a.columns[name], a2.columns[name], err_msg=name)
    assert not np.array_equal(a.columns["current_back_a"], b.columns["current_back_a"])
    noise = np.concatenate([a.columns["current_back_a"], a.columns["current_front_a"]])
    assert np.std(noise) == pytest.approx(0.05, rel=0.1)
    assert abs(np.mean(noise)) < 4 * 0.05 / math.sqrt(noise.size)


def test_rig_stall_belt_creeps_to_the_edge_of_the_stiction_band(tmp_path, capsys):
    """`rig stall`: torso and legs held, the amplifier at its current limit, so the printed
    hip torque is tau = N eta K_T i_max. The motor joint slips while the belt is loaded
    beyond the band its stiction holds, (tau -+ N tau_s) / k_b, so the deflection creeps
    from 0 towards the band's lower edge as a first-order lag,
    delta(t) = delta_lo (1 - exp(-t k_b / (c_b + N^2 b_J))), and stays below the paper's
    ~8 deg. The log's motor-side encoder angle (leg held at 0) is that deflection, the
    logged current i_max, and the printed numbers are the log's."""
    out = tmp_path / "stall"
    assert main(["rig", "stall", "--duration", "4", "--no-noise", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    robot = RobotParameters()
    N = robot.gear_ratio
    tau = N * robot.gearbox_efficiency * robot.sprocket_efficiency * robot.torque_constant \
        * robot.current_limit
    lo = (tau - N * robot.joint_stiction) / robot.belt_stiffness
    hi = (tau + N * robot.joint_stiction) / robot.belt_stiffness
    lag = (robot.belt_damping + N * N * robot.joint_damping) / robot.belt_stiffness
    assert f"hip torque {tau:.2f} N m per physical leg" in printed
    assert (f"static band of the motor stiction {math.degrees(lo):.3f} .. "
            f"{math.degrees(hi):.3f} deg") in printed
    assert f"c_b/k_b = {robot.belt_damping / robot.belt_stiffness:.3f} s" in printed

    log = load_log(out / "stall.csv.gz")
    t = log.columns["t"]
    assert t[-1] == pytest.approx(4.0)
    creep = lo * (1.0 - np.exp(-t / lag))
    for leg in ("back", "front"):
        delta = log.columns[f"phi_{leg}_rad"]
        np.testing.assert_allclose(delta, creep, rtol=0, atol=1e-3 * lo)
        assert np.all(delta <= hi) and math.degrees(delta.max()) < 8.0
        np.testing.assert_array_equal(log.columns[f"current_{leg}_a"], robot.current_limit)
    deflection = float(printed.split("belt deflection after 4 s: ")[1].split(" deg")[0])
    assert deflection == pytest.approx(math.degrees(log.columns["phi_back_rad"][-1]), abs=1e-3)


def test_rig_flight_steps_servo_follows_the_default_schedule(tmp_path):
    """`rig flight-steps`: the log records the touchdown-angle commands of the default
    schedule (back 19, -15, 30, 0 deg; front 21, 35, -10, 10 deg from 0, 0.4, 0.8, 1.2 s;
    1.6 s), the legs stay in flight, and by the end of each step the flight servo holds
    the motor-side angle at the command within the gravity-load error m g d / kp."""
    out = tmp_path / "fs"
    assert main(["rig", "flight-steps", "--no-noise", "--out", str(out)]) == 0
    c = load_log(out / "flight-steps.csv.gz").columns
    t = c["t"]
    assert t[-1] == pytest.approx(1.6)
    schedule = {"back": (19.0, -15.0, 30.0, 0.0), "front": (21.0, 35.0, -10.0, 10.0)}
    robot, ctrl = RobotParameters(), ControllerParameters()
    for leg, angles in schedule.items():
        assert np.all(c[f"leg_state_{leg}"] == 0)
        kp = getattr(ctrl, f"flight_kp_{leg}")
        droop = robot.leg_mass * robot.gravity * robot.leg_com_distance / kp
        for j, (t0, t1) in enumerate(zip((0.0, 0.4, 0.8, 1.2), (0.4, 0.8, 1.2, 1.6))):
            k = (t >= t0 + 1e-6) & (t < t1 - 1e-6)
            np.testing.assert_allclose(c[f"touchdown_cmd_{leg}_rad"][k],
                                       math.radians(angles[j]), atol=1e-6)
            last = np.flatnonzero(k)[-1]
            assert abs(c[f"phi_{leg}_rad"][last] - math.radians(angles[j])) < droop + 2e-3


def test_rig_takes_the_robot_file_and_refuses_bad_options(tmp_path, capsys):
    """--robot sets the hip unit the rig runs (the log's true parameters say so, SI);
    a malformed --release, a release angle outside (-90, 90) deg and a duration that ends
    before the last flight step are usage errors (exit 2, the field named, nothing
    written)."""
    robot_file = tmp_path / "robot.toml"
    robot_file.write_text('[transmission]\nbelt_stiffness = { value = 9.0, unit = "N m/deg" }\n')
    out = tmp_path / "out"
    assert main(["rig", "free-swing", "--duration", "0.2", "--robot", str(robot_file),
                 "--out", str(out)]) == 0
    meta = load_log(out / "free-swing.csv.gz").meta
    assert meta["true_parameters"]["belt_stiffness"] == pytest.approx(9.0 * 180.0 / math.pi)
    capsys.readouterr()

    bad = tmp_path / "bad"
    for argv, text in ((["free-swing", "--release", "abc"], "--release 'abc'"),
                       (["free-swing", "--release", "100,0"], "release_angle_back"),
                       (["flight-steps", "--duration", "0.5"], "step_times")):
        assert main(["rig", *argv, "--out", str(bad)]) == 2
        err = capsys.readouterr().err
        assert text in err and "Traceback" not in err
        assert not bad.exists() or not any(bad.iterdir())
