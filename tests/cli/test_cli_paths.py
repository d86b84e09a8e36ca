"""Tests of command-line paths that tests/cli/test_cli.py does not cover: `scoutsim rig` with
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
from scoutsim._core.model import layout as L
from scoutsim.cli import main
from scoutsim.io.run_directory import check_run_directory
from scoutsim.validation.log_reading import load_log

DT = 1e-3  # the Table I control period [s]: the rigs sample at it


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
    proc = subprocess.run(
        [sys.executable, "-m", "scoutsim", "--version"], capture_output=True, text=True, timeout=120
    )
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
    kg = (
        robot.leg_mass * robot.leg_com_distance + toe_mass * robot.leg_rest_length
    ) * robot.gravity
    b = (
        N
        * N
        * robot.efficiency
        * robot.torque_constant
        * robot.speed_constant
        / robot.armature_resistance
        + N * N * robot.joint_damping
    )
    return kg, b


def test_rig_free_swing_with_shorted_leads_creeps_at_the_back_emf_balance(tmp_path, capsys):
    """`rig free-swing --motor short --toe-mass --release --duration --no-noise`: the log
    starts at the release angles, lasts the duration, and shows the shorted winding's
    physics: current i = -K_w N dalpha / R_A, and the leg (with the given toe mass) creeps
    where gravity balances back-EMF, joint damping and stiction,
    (m d + m_t l0) g sin(phi) = b |dphi| + N tau_s."""
    out = tmp_path / "rig"
    code = main(
        [
            "rig",
            "free-swing",
            "--motor",
            "short",
            "--toe-mass",
            "2",
            "--release",
            "60,0",
            "--duration",
            "2",
            "--no-noise",
            "--out",
            str(out),
        ]
    )
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
    k = c["t"] > 1.0  # after the transient of the release
    phi, rate = c["phi_back_rad"][k], c["dphi_back_rad_s"][k]
    np.testing.assert_allclose(
        c["current_back_a"][k],
        -robot.speed_constant * N * rate / robot.armature_resistance,
        rtol=1e-3,
    )
    kg, b = _swing_balance(robot, toe_mass=2.0)
    np.testing.assert_allclose(rate, -(kg * np.sin(phi) - N * robot.joint_stiction) / b, rtol=0.01)


def test_rig_free_swing_open_leads_carry_no_current_and_noise_follows_the_seed(tmp_path):
    """Open leads (the default): no current flows (noise-free log: exactly 0). With the
    default sensor noise the current channel is white noise of the stated 0.05 A; the same
    --seed gives the same log, another seed another one."""

    def log(name, *extra):
        out = tmp_path / name
        assert main(["rig", "free-swing", "--duration", "0.5", "--out", str(out), *extra]) == 0
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
    tau = (
        N
        * robot.gearbox_efficiency
        * robot.sprocket_efficiency
        * robot.torque_constant
        * robot.current_limit
    )
    lo = (tau - N * robot.joint_stiction) / robot.belt_stiffness
    hi = (tau + N * robot.joint_stiction) / robot.belt_stiffness
    lag = (robot.belt_damping + N * N * robot.joint_damping) / robot.belt_stiffness
    assert f"hip torque {tau:.2f} N m per physical leg" in printed
    assert (
        f"static band of the motor stiction {math.degrees(lo):.3f} .. {math.degrees(hi):.3f} deg"
    ) in printed
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
            np.testing.assert_allclose(
                c[f"touchdown_cmd_{leg}_rad"][k], math.radians(angles[j]), atol=1e-6
            )
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
    assert (
        main(
            [
                "rig",
                "free-swing",
                "--duration",
                "0.2",
                "--robot",
                str(robot_file),
                "--out",
                str(out),
            ]
        )
        == 0
    )
    meta = load_log(out / "free-swing.csv.gz").meta
    assert meta["true_parameters"]["belt_stiffness"] == pytest.approx(9.0 * 180.0 / math.pi)
    capsys.readouterr()

    bad = tmp_path / "bad"
    for argv, text in (
        (["free-swing", "--release", "abc"], "--release 'abc'"),
        (["free-swing", "--release", "100,0"], "release_angle_back"),
        (["flight-steps", "--duration", "0.5"], "step_times"),
    ):
        assert main(["rig", *argv, "--out", str(bad)]) == 2
        err = capsys.readouterr().err
        assert text in err and "Traceback" not in err
        assert not bad.exists() or not any(bad.iterdir())


# -----------------------------------------------------------------------------------------
# scoutsim identify
# -----------------------------------------------------------------------------------------
#: the "true" hip unit of `identify --example`: Table II times these factors
#: (docs/identification.md, section 3)
EXAMPLE_FACTORS = {
    "drive_gear_inertia": 1.5,
    "driven_gear_inertia": 0.7,
    "joint_stiction": 1.6,
    "joint_damping": 0.6,
    "belt_stiffness": 1.3,
    "belt_damping": 0.8,
}


def test_identify_example_recovers_the_known_hip_unit(tmp_path, capsys):
    """`identify --example`: virtual free-swing and flight-step logs made with Table II x
    the documented factors, fitted from Table II. The report's true values are those;
    the clamped-torso rigs see only the reflected inertia J_2 + N^2 J_1, so the two gear
    inertias are reported not identifiable while their combination is pinned; the other
    four are identified close to the truth; the residuals are as large as the stated
    sensor noise (scale ~ 1)."""
    out = tmp_path / "idf"
    code = main(
        [
            "identify",
            "--example",
            "--starts",
            "2",
            "--local",
            "1",
            "--no-plots",
            "--no-progress",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    printed = capsys.readouterr().out
    assert "virtual logs of the free-swing and flight-steps rig(s)" in printed
    assert f"wrote {out / 'identified.json'}" in printed
    assert {p.name for p in out.iterdir()} == {
        "free-swing.csv.gz",
        "flight-steps.csv.gz",
        "identified.json",
    }
    rep = json.loads((out / "identified.json").read_text())
    assert rep["rigs"] == ["free-swing", "flight-steps"]
    table2 = RobotParameters()
    par = rep["parameters"]
    assert set(par) == set(EXAMPLE_FACTORS)
    for name, factor in EXAMPLE_FACTORS.items():
        assert par[name]["true"] == pytest.approx(getattr(table2, name) * factor, rel=1e-12)
    assert not par["drive_gear_inertia"]["identifiable"]
    assert not par["driven_gear_inertia"]["identifiable"]
    N = table2.gear_ratio
    reflected = par["driven_gear_inertia"]["true"] + N * N * par["drive_gear_inertia"]["true"]
    combo = rep["combinations"]["reflected_gear_inertia"]
    assert combo["true"] == pytest.approx(reflected, rel=1e-12)
    assert combo["value"] == pytest.approx(reflected, rel=1e-3)
    for name, rel in (
        ("joint_stiction", 5e-3),
        ("joint_damping", 5e-3),
        ("belt_stiffness", 0.05),
        ("belt_damping", 0.05),
    ):
        assert par[name]["identifiable"], name
        assert par[name]["value"] == pytest.approx(par[name]["true"], rel=rel), name
    assert rep["residual_scale"] == pytest.approx(1.0, abs=0.05)


def test_rig_log_then_identify_rig_flight_steps_finds_the_joint_damping(tmp_path, capsys):
    """A flight-step log written by `scoutsim rig flight-steps` with a known joint damping
    (robot file, 0.6 x Table II), fitted by `identify LOG --rig flight-steps --params
    joint_damping` from Table II: the flight steps determine the joint damping
    (docs/identification.md), so it comes back identifiable and within 1 % of the file's
    value; --json prints identified.json; the fit figure is written."""
    robot_file = tmp_path / "robot.toml"
    robot_file.write_text(
        '[transmission]\njoint_damping = { value = 3.72e-7, unit = "N m/(deg/s)" }\n'
    )
    true = 3.72e-7 * 180.0 / math.pi  # N m s/rad
    logs = tmp_path / "logs"
    assert main(["rig", "flight-steps", "--robot", str(robot_file), "--out", str(logs)]) == 0
    capsys.readouterr()
    out = tmp_path / "fit"
    code = main(
        [
            "identify",
            str(logs / "flight-steps.csv.gz"),
            "--rig",
            "flight-steps",
            "--params",
            "joint_damping",
            "--starts",
            "2",
            "--local",
            "1",
            "--json",
            "--no-progress",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed == json.loads((out / "identified.json").read_text())
    assert printed["rigs"] == ["flight-steps"]
    jd = printed["parameters"]["joint_damping"]
    assert list(printed["parameters"]) == ["joint_damping"]
    assert jd["true"] == pytest.approx(true, rel=1e-12)
    assert jd["start"] == pytest.approx(RobotParameters().joint_damping, rel=1e-12)
    assert jd["identifiable"]
    assert jd["value"] == pytest.approx(true, rel=0.01)
    assert (out / "fit_1.png").read_bytes().startswith(b"\x89PNG")


# -----------------------------------------------------------------------------------------
# scoutsim sweep
# -----------------------------------------------------------------------------------------
def _sweep(out, *argv):
    return main(
        ["sweep", *argv, "--model", "I", "--workers", "1", "--no-progress", "--out", str(out)]
    )


def test_sweep_orbit_records_each_bounding_points_periodic_orbit(tmp_path, capsys):
    """`sweep --orbit` on a steadily bounding point (Model II, 5 s): the orbit columns say
    a periodic orbit was found; its period is a whole number of control periods and the
    inverse of the run's steady stride frequency; "stable" means spectral radius < 1; the
    Newton residual is below the sweep's orbit tolerance; the printed count agrees."""
    from scoutsim.analysis.sweep import ORBIT_COLUMNS, ORBIT_TOL

    out = tmp_path / "sw"
    code = main(
        [
            "sweep",
            "--grid",
            "controller.touchdown_angle_front_deg=21:21:1",
            "--model",
            "II",
            "--duration",
            "5",
            "--orbit",
            "--workers",
            "1",
            "--no-progress",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    printed = capsys.readouterr().out
    (row,) = _rows(out / "sweep.csv")
    assert list(row)[-len(ORBIT_COLUMNS) :] == list(ORBIT_COLUMNS)
    assert row["steady_bounding"] == "True" and row["orbit_status"] == "ok"
    period = float(row["orbit_period_s"])
    assert period / DT == pytest.approx(round(period / DT), abs=1e-9)
    strides = int(float(row["orbit_strides"]))
    assert period / strides == pytest.approx(1.0 / float(row["stride_frequency_hz"]), rel=2e-3)
    assert (row["orbit_stable"] == "True") == (float(row["orbit_spectral_radius"]) < 1.0)
    # below the tolerance, or accepted within the map's own rounding noise
    noise = float(row["orbit_residual_noise"])
    assert float(row["orbit_residual"]) < ORBIT_TOL or float(row["orbit_residual"]) <= 10 * noise
    stable = int(row["orbit_stable"] == "True")
    assert f"periodic orbits found and stable: {stable} of 1 bounding points" in printed


def test_sweep_orbit_skips_a_point_that_is_not_bounding(tmp_path, capsys):
    """A run too short for steady bounding gets no orbit, with the reason, not an error."""
    out = tmp_path / "sw"
    assert (
        _sweep(
            out,
            "--grid",
            "controller.touchdown_angle_front_deg=21:21:1",
            "--duration",
            "0.3",
            "--orbit",
        )
        == 0
    )
    (row,) = _rows(out / "sweep.csv")
    assert row["outcome"] == "completed" and row["steady_bounding"] == "False"
    assert row["orbit_status"] == "no orbit: not steady bounding"
    assert row["orbit_period_s"] == row["orbit_stable"] == ""
    assert "periodic orbits found and stable: 0 of 0 bounding points" in capsys.readouterr().out


def test_sweep_no_resume_recomputes_every_point(tmp_path, capsys):
    """A second sweep into the same directory takes finished points from points.jsonl;
    with --no-resume it recomputes every point instead: a value planted in the checkpoint
    shows up in the resumed table and is gone after --no-resume, and the checkpoint holds
    one record per point again."""
    out = tmp_path / "sw"
    args = ["--grid", "controller.touchdown_angle_front_deg=19:21:2", "--duration", "0.2"]
    assert _sweep(out, *args) == 0
    first = _rows(out / "sweep.csv")
    assert "(0 resumed from" in capsys.readouterr().out
    ck = out / "points.jsonl"
    records = [json.loads(line) for line in ck.read_text().splitlines()]
    assert len(records) == 2
    for rec in records:
        rec["row"]["average_speed_m_s"] = 99.0
    ck.write_text("".join(json.dumps(rec) + "\n" for rec in records))

    assert _sweep(out, *args) == 0
    assert "(2 resumed from" in capsys.readouterr().out
    assert [r["average_speed_m_s"] for r in _rows(out / "sweep.csv")] == ["99.0", "99.0"]

    assert _sweep(out, *args, "--no-resume") == 0
    assert "(0 resumed from" in capsys.readouterr().out
    again = _rows(out / "sweep.csv")
    assert again == first
    assert len(ck.read_text().splitlines()) == 2
    assert check_run_directory(out)["status"] == "complete"


def test_sweep_random_sample_runs_each_drawn_point(tmp_path, capsys):
    """`sweep --random NAME=LOW:HIGH --samples N --seed S`: N points drawn within the
    bounds (kept in degrees in the _deg column; each run converts to rad), the same for the same seed and different for
    another; each row is the run of its point (its average speed is that of a direct
    simulate() with that parameter); no map for a random sample; the directory is
    complete."""

    def sample(name, seed):
        out = tmp_path / name
        assert (
            _sweep(
                out,
                "--random",
                "controller.touchdown_angle_front_deg=19:23",
                "--samples",
                "3",
                "--seed",
                str(seed),
                "--duration",
                "0.3",
            )
            == 0
        )
        return out, _rows(out / "sweep.csv")

    out, rows = sample("a", 5)
    assert "scoutsim sweep: 3 points of model I" in capsys.readouterr().out
    values = [float(r["controller.touchdown_angle_front_deg"]) for r in rows]
    assert len(set(values)) == 3
    assert all(19.0 <= v <= 23.0 for v in values)
    assert all(r["outcome"] == "completed" for r in rows)
    assert not (out / "map.png").exists()
    assert set(check_run_directory(out)["files"]) >= {"sweep.csv"}
    assert check_run_directory(out)["status"] == "complete"

    assert [r["controller.touchdown_angle_front_deg"] for r in sample("b", 5)[1]] == [
        r["controller.touchdown_angle_front_deg"] for r in rows
    ]
    assert [float(r["controller.touchdown_angle_front_deg"]) for r in sample("c", 6)[1]] != values

    direct = scoutsim.simulate(
        None,
        ControllerParameters(touchdown_angle_front=math.radians(values[0])),
        None,
        0.3,
        model="I",
    )
    assert float(rows[0]["average_speed_m_s"]) == pytest.approx(
        (direct.x[-1] - direct.x[0]) / direct.t[-1], rel=1e-12
    )


# -----------------------------------------------------------------------------------------
# scoutsim orbit --model I, scoutsim run --model ideal
# -----------------------------------------------------------------------------------------
def test_orbit_model_I_prints_a_periodic_orbit(tmp_path, capsys):
    """`orbit --model I --json`: the printed section state is a periodic orbit. Resumed
    with simulate() (the section's discrete modes from a Model I run at the sample after
    the controller detects back-leg lift-off: back leg just lifted off, front leg in
    stance), the controller detects the next back-leg lift-off one sample before the
    period ends, and at the period's end the state is back where it started; the period is a whole
    number of control periods; the mean speed is the travel over the period; "stable"
    is spectral radius < 1, the spectral radius the largest |multiplier|."""
    # (6 s from the default start the run passes near the period-1 orbit; it settles on
    # the 2-stride cycle, test_orbit_model_I_settles_on_a_two_stride_cycle)
    assert (
        main(
            [
                "orbit",
                "--model",
                "I",
                "--duration",
                "6",
                "--strides",
                "1",
                "--json",
                "--no-progress",
            ]
        )
        == 0
    )
    orb = json.loads(capsys.readouterr().out)
    assert orb["strides_per_period"] == 1
    period = orb["period_s"]
    n = round(period / DT)
    assert period == pytest.approx(n * DT, abs=1e-12)
    assert orb["residual"] < 1e-9
    mags = [abs(complex(re, im)) for re, im in orb["eigenvalues"]]
    assert orb["spectral_radius"] == pytest.approx(max(mags), rel=1e-12)
    assert orb["stable"] == (orb["spectral_radius"] < 1.0)

    run = scoutsim.simulate(None, None, None, 2.0, model="I")
    k_lo = int(round(run.event_times("controller_liftoff", "back")[-1] / DT)) + 1
    modes = run.hybrid_state(k_lo)
    z = orb["state"]
    s = np.array([0.0] + [z[name] for name in L.STATE_NAMES[1:]])
    start = HybridState(
        state=s,
        leg_states=modes.leg_states,
        contact_modes=modes.contact_modes,
        motor_modes=modes.motor_modes,
        slide_directions=modes.slide_directions,
        toe_anchors=(z["anchor_back_rel"], z["anchor_front_rel"]),
    )
    r = scoutsim.simulate(
        None,
        None,
        start,
        period + 0.05,
        model="I",
        integrator=IntegratorSettings(rtol=1e-11, atol=1e-12),
    )
    np.testing.assert_allclose(
        r.event_times("controller_liftoff", "back"), [period - DT], atol=1e-12
    )
    assert r.hybrid_state(n).leg_states == modes.leg_states
    np.testing.assert_allclose(r.state[n, 1:], s[1:], rtol=0, atol=1e-8)
    assert (r.x[n] - r.x[0]) / period == pytest.approx(orb["mean_speed_m_s"], rel=1e-8)


def test_orbit_model_I_settles_on_a_two_stride_cycle(capsys):
    """Model I under the Table I law has two stable gaits: the period-1 orbit of 207
    control periods (above) and a cycle of two strides of 207 and 205 periods, on which a
    long run from the default start settles. `orbit` after the default 12 s settling finds
    the cycle the run is on; the long run's strides independently alternate 207 / 205."""
    run = scoutsim.simulate(None, None, None, 30.0, model="I")
    strides = np.round(np.diff(run.event_times("controller_liftoff", "back")) / DT).astype(int)
    assert sorted(set(strides[-20:])) == [205, 207]
    assert np.all(strides[-20:][1:] != strides[-20:][:-1])
    assert main(["orbit", "--model", "I", "--json", "--no-progress"]) == 0
    orb = json.loads(capsys.readouterr().out)
    assert orb["strides_per_period"] == 2
    assert orb["period_s"] == pytest.approx((207 + 205) * DT, abs=1e-12)
    assert orb["residual"] < 1e-9 and orb["stable"]


def test_run_model_ideal_limits_torque_only_by_the_current_limit(tmp_path, capsys):
    """`run --model ideal`: the summary and provenance say ideal; the ideal actuator has
    no torque-speed line, only |tau| <= N eta K_T i_max, so the applied hip torque is the
    commanded one clipped there and the current i = tau / (N eta K_T) clipped at i_max;
    it has no belt, so the motor-side angle is the leg angle."""
    out = tmp_path / "ideal"
    assert (
        main(["run", "--model", "ideal", "--duration", "0.6", "--out", str(out), "--no-progress"])
        == 0
    )
    assert json.loads((out / "summary.json").read_text())["model"] == "ideal"
    r = scoutsim.SimulationResult.load(out)
    assert r.provenance["model"] == "ideal" and r.outcome == "completed"
    robot = RobotParameters()
    per_amp = robot.gear_ratio * robot.efficiency * robot.torque_constant
    tau_max = per_amp * robot.current_limit
    clipped = 0
    for leg in ("back", "front"):
        cmd = r.hip_torque_commanded(leg)
        np.testing.assert_allclose(
            r.hip_torque_applied(leg), np.clip(cmd, -tau_max, tau_max), rtol=1e-12, atol=1e-12
        )
        np.testing.assert_allclose(
            r.motor_current(leg),
            np.clip(cmd / per_amp, -robot.current_limit, robot.current_limit),
            rtol=1e-12,
            atol=1e-12,
        )
        np.testing.assert_array_equal(r.motor_angle(leg), r.leg_angle(leg))
        clipped += int(np.sum(np.abs(cmd) > tau_max))
    assert clipped > 0  # the limit was reached, so the clipping was exercised


def test_sweep_settings_it_refuses_are_a_usage_error(tmp_path, capsys):
    """Two names for the same field (radians and degrees): a usage error (exit 2) that
    says so, not a traceback."""
    code = main(
        [
            "sweep",
            "--grid",
            "controller.touchdown_angle_front=0.33:0.4:2",
            "--grid",
            "controller.touchdown_angle_front_deg=19:23:2",
            "--duration",
            "1",
            "--out",
            str(tmp_path / "s"),
        ]
    )
    assert code == 2
    assert "set the same field" in capsys.readouterr().err
