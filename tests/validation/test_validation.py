"""Tests of scoutsim.validation: log format and loader, measurement chain, stride metrics of
logs, the Fig. 12 error assessment and the `scoutsim compare` CLI."""

import csv
import gzip
import math

import numpy as np
import pytest

from scoutsim import RobotParameters, simulate
from scoutsim.state import InitialState
from scoutsim.validation import (
    ExperimentLog,
    LaserGeometry,
    LogError,
    SensorNoise,
    fft_lowpass,
    load_dataset,
    load_log,
    log_strides,
    save_log,
    to_log,
)
from scoutsim.validation.errors import (
    CSV_COLUMNS,
    ERROR_METRICS,
    ModelRun,
    assess_errors,
    percent_errors,
)
from scoutsim.validation.measurement import laser_ranges, pitch_height_from_lasers

#: scoutsim's earlier default start (4 deg nose-up, no pitch motion), at the edge of the
#: basin: Model I falls from it at about 1.4 s (the fallen-model paths of the comparison)
FALLING_START = InitialState(theta=math.radians(4.0), dtheta=0.0)

DURATION = 10.0


@pytest.fixture(scope="module")
def sim():
    """One 10 s Model II run at mu = 0.8, shared by the tests."""
    return simulate(duration=DURATION, model="II", friction_coefficient=0.8)


@pytest.fixture(scope="module")
def sim_log(sim):
    return to_log(sim)


@pytest.fixture(scope="module")
def perturbed():
    robot = RobotParameters()
    robot = robot.replace(
        leg_damping=1.2 * robot.leg_damping, torso_inertia=0.9 * robot.torso_inertia
    )
    return simulate(robot, duration=DURATION, model="II", friction_coefficient=0.8)


def _run(model, result, like):
    """A ModelRun of an already simulated result, measured like ``like``."""
    g = log_strides(
        to_log(
            result,
            geometry=LaserGeometry(
                like.meta["laser_half_spacing_m"], like.meta["laser_mount_offset_m"]
            ),
        )
    )
    return ModelRun(model, result.outcome, result.t_end, g, result=result)


# -----------------------------------------------------------------------------------------
# measurement chain
# -----------------------------------------------------------------------------------------
def test_lowpass_keeps_2hz_and_removes_50hz():
    fs = 1000.0
    t = np.arange(0.0, 3.3, 1 / fs)
    inner = slice(300, -300)  # edge effects: the first and last 0.3 s (EDGE_S)
    for phase in np.linspace(0, 2 * np.pi, 7):
        slow = np.sin(2 * np.pi * 2 * t + phase)
        fast = np.sin(2 * np.pi * 50 * t + phase)
        assert np.max(np.abs(fft_lowpass(slow, fs) - slow)[inner]) < 0.01
        assert np.max(np.abs(fft_lowpass(fast, fs))[inner]) < 0.01
        # and a sum: the 2 Hz part survives, the 50 Hz part goes
        both = fft_lowpass(slow + fast, fs)
        assert np.max(np.abs(both - slow)[inner]) < 0.01
    # brick-wall variant too
    slow = np.sin(2 * np.pi * 2 * t + 0.3)
    assert np.max(np.abs(fft_lowpass(slow, fs, transition_hz=0.0) - slow)[inner]) < 0.01


def test_lasers_invert_exactly():
    rng = np.random.default_rng(0)
    y = rng.uniform(0.2, 0.4, 100)
    th = rng.uniform(-0.5, 0.5, 100)
    geo = LaserGeometry(0.34, 0.015)
    rf, rb = laser_ranges(y, th, geo)
    th2, y2 = pitch_height_from_lasers(rf, rb, geo)
    np.testing.assert_allclose(th2, th, atol=1e-12)
    np.testing.assert_allclose(y2, y, atol=1e-12)
    # level torso: both lasers read the height minus the mount offset
    rf, rb = laser_ranges(0.3, 0.0, geo)
    assert rf == pytest.approx(0.285) and rb == pytest.approx(0.285)


def test_to_log_is_what_the_robot_logs(sim, sim_log):
    lg = sim_log
    assert lg.synthetic
    assert len(lg.t) == len(sim.t)
    np.testing.assert_array_equal(lg.leg_state("back"), sim.leg_state("back"))
    # torque from current, N eta K_T i
    np.testing.assert_allclose(
        lg.hip_torque("front"), sim.hip_torque_applied("front"), rtol=1e-9, atol=1e-9
    )
    # measured pitch: the 15 Hz filtered true pitch (inside the record)
    inner = slice(500, -500)
    err = np.abs(lg.pitch - sim.pitch)[inner]
    assert np.max(err) < math.radians(1.0)
    assert np.max(np.abs(lg.height - sim.height)[inner]) < 2e-3
    # lift-offs from the leg states
    lo = lg.liftoff_times("back")
    assert len(lo) > 20


def test_noise_is_seeded(sim):
    a = to_log(sim, noise=SensorNoise(), seed=3)
    b = to_log(sim, noise=SensorNoise(), seed=3)
    np.testing.assert_array_equal(a.columns["laser_front_m"], b.columns["laser_front_m"])
    assert not np.array_equal(a.columns["laser_front_m"], to_log(sim).columns["laser_front_m"])


# -----------------------------------------------------------------------------------------
# strides and errors
# -----------------------------------------------------------------------------------------
def test_log_strides_have_gait_metric_names(sim_log, sim):
    g = log_strides(sim_log)
    assert g.n_steady_strides >= 7
    ref = sim.gait()
    # controller-detected strides have the plant's stride frequency to within 1 %
    assert g.stride_frequency_hz == pytest.approx(ref.stride_frequency_hz, rel=0.01)
    for k in ERROR_METRICS:
        assert math.isfinite(g.means[k])


def test_self_comparison_gives_zero_error(sim, sim_log):
    # a simulation exported through the measurement chain and compared with itself (also
    # simulated and measured the same way): exactly 0 % in every metric, mean and max
    exp = log_strides(sim_log).steady_strides
    table = assess_errors(exp, {"II": _run("II", sim, sim_log)})
    for metric in ERROR_METRICS:
        row = table.row("II", metric)
        assert row.n_strides == len(exp)
        assert row.percent_error_of_means == 0.0
        assert row.mean_percent_error == 0.0, metric
        assert row.max_percent_error == 0.0, metric


def test_steady_model_is_compared_with_every_experimental_stride(sim, sim_log):
    # a model whose strides are all alike (a steady limit cycle) pairs every experimental
    # stride with that one value: the paper's comparison, errors = the experiment's scatter
    # about the model value
    run = _run("II", sim, sim_log)
    from scoutsim.analysis.strides import Stride
    from scoutsim.validation.log_strides import LogGait

    exp = log_strides(sim_log).steady_strides
    for metric in ERROR_METRICS:
        x = np.array([s[metric] for s in exp])
        m = float(np.median(x))
        one = Stride(
            index=0,
            t_start=0.0,
            t_end=1.0,
            period_s=1.0,
            **{k: (m if k == metric else run.gait.means[k]) for k in ERROR_METRICS},
            mean_speed_m_s=math.nan,
            steady=True,
        )
        steady = ModelRun("II", "completed", 10.0, LogGait(strides=[one] * 5, transient_s=0.0))
        row = assess_errors(exp, {"II": steady}).row("II", metric)
        scatter = 100 * np.abs(x - m) / np.abs(x)
        assert row.mean_percent_error == pytest.approx(float(np.mean(scatter)), rel=1e-12)
        assert row.max_percent_error == pytest.approx(float(np.max(scatter)), rel=1e-12)


def test_rank_pairing():
    from scoutsim.validation.errors import rank_paired_model_values

    x = np.array([3.0, 1.0, 2.0])
    # equal sizes: rank to rank, aligned with the experiment's order
    assert list(rank_paired_model_values([20.0, 30.0, 10.0], x)) == [30.0, 10.0, 20.0]
    # a shifted copy is paired with its own counterparts
    y = np.array([0.3, 0.1, 0.7, 0.5])
    assert np.array_equal(rank_paired_model_values(y[::-1] + 1.0, y), y + 1.0)
    # different sizes: quantiles at the experiment's plotting positions
    m = rank_paired_model_values([0.0, 1.0], [5.0, 6.0, 7.0, 8.0])
    assert np.all(np.diff(m) >= 0) and m[0] == 0.0 and m[-1] == 1.0
    assert m[1] == pytest.approx(0.25) and m[2] == pytest.approx(0.75)
    with pytest.raises(ValueError):
        rank_paired_model_values([], x)


def test_perturbed_parameters_give_nonzero_errors(perturbed, sim):
    exp_log = to_log(perturbed)
    exp = log_strides(exp_log).steady_strides
    assert len(exp) >= 7
    table = assess_errors(exp, {"II": _run("II", sim, exp_log)})
    errs = {m: table.row("II", m).percent_error_of_means for m in ERROR_METRICS}
    assert all(e > 0 for e in errs.values()), errs
    assert errs["stride_frequency_hz"] > 1.0


def test_fallen_model_is_reported_not_crashing(sim_log):
    fell = simulate(initial_state=FALLING_START, duration=3.0, model="I", friction_coefficient=0.8)
    assert fell.outcome == "fell"
    exp = log_strides(sim_log).steady_strides
    run = ModelRun("I", fell.outcome, fell.t_end, log_strides(to_log(fell)), result=fell)
    table = assess_errors(exp, {"I": run})
    r = table.row("I", "stride_frequency_hz")
    assert r.n_strides == 0 and math.isnan(r.mean_percent_error)
    assert "fell" in table.format()


def test_percent_errors_relative_to_experiment():
    np.testing.assert_allclose(percent_errors(1.1, [1.0, 2.0]), [10.0, 45.0])
    assert math.isnan(percent_errors(1.0, [0.0])[0])


def test_table_outputs(sim, sim_log, tmp_path):
    exp = log_strides(sim_log).steady_strides
    table = assess_errors(exp, {"II": _run("II", sim, sim_log)})
    p = table.to_csv(tmp_path / "errors.csv")
    with open(p) as fh:
        rows = list(csv.reader(fh))
    assert tuple(rows[0]) == CSV_COLUMNS
    assert len(rows) == 1 + len(ERROR_METRICS)
    md = table.to_markdown()
    assert "| model |" in md and "stride frequency" in md


# -----------------------------------------------------------------------------------------
# log files
# -----------------------------------------------------------------------------------------
def _write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def _small_log(n=50, **over):
    t = np.arange(n) * 1e-3
    cols = {
        "t": t,
        "laser_front_m": np.full(n, 0.3),
        "laser_back_m": np.full(n, 0.3),
        "phi_back_rad": np.zeros(n),
        "phi_front_rad": np.zeros(n),
        "dphi_back_rad_s": np.zeros(n),
        "dphi_front_rad_s": np.zeros(n),
        "current_back_a": np.zeros(n),
        "current_front_a": np.zeros(n),
        "leg_state_back": np.zeros(n),
        "leg_state_front": np.ones(n),
    }
    cols.update(over)
    return ExperimentLog(cols, {"source": "test"})


def test_round_trip_csv_gz(sim_log, tmp_path):
    p = save_log(sim_log, tmp_path / "run.csv.gz")
    back = load_log(p)
    assert back.synthetic and back.meta["laser_half_spacing_m"] == 0.35
    np.testing.assert_allclose(back.t, sim_log.t)
    np.testing.assert_allclose(back.pitch, sim_log.pitch, atol=1e-6)
    g0, g1 = log_strides(sim_log), log_strides(back)
    assert g1.n_steady_strides == g0.n_steady_strides


def test_round_trip_parquet(tmp_path):
    pytest.importorskip("pyarrow")
    lg = _small_log()
    p = save_log(lg, tmp_path / "run.parquet")
    back = load_log(p)
    assert back.meta["source"] == "test"
    np.testing.assert_array_equal(back.columns["leg_state_front"], 1.0)


def test_parquet_without_pyarrow_says_how_to_install(tmp_path, monkeypatch):
    import builtins

    real_import = builtins.__import__

    def fake_import(name, *a, **k):
        if name.startswith("pyarrow"):
            raise ImportError("no pyarrow")
        return real_import(name, *a, **k)

    p = tmp_path / "x.parquet"
    p.write_bytes(b"PAR1")
    monkeypatch.setattr(builtins, "__import__", fake_import)
    with pytest.raises(LogError, match="pip install pyarrow"):
        load_log(p)


@pytest.mark.parametrize(
    "mutate, column, row, words",
    [
        (lambda c: c.pop("phi_back_rad"), "phi_back_rad", None, "missing column"),
        (lambda c: c.pop("laser_back_m"), "laser_back_m", None, "missing column"),
        (
            lambda c: c.__setitem__(
                "t", np.r_[np.arange(10) * 1e-3, 0.005, np.arange(11, 50) * 1e-3]
            ),
            "t",
            11,
            "does not increase",
        ),
        (
            lambda c: c["laser_front_m"].__setitem__(slice(20, 25), np.nan),
            "laser_front_m",
            21,
            "gap of 5",
        ),
        (lambda c: c["phi_front_rad"].__setitem__(7, 21.0), "phi_front_rad", 8, "degrees"),
        (lambda c: c["laser_back_m"].__setitem__(3, 300.0), "laser_back_m", 4, "millimetres"),
        (lambda c: c["leg_state_back"].__setitem__(30, 3.0), "leg_state_back", 31, "leg state"),
    ],
)
def test_bad_logs_name_file_column_and_row(tmp_path, mutate, column, row, words):
    lg = _small_log()
    cols = {k: v.copy() for k, v in lg.columns.items()}
    mutate(cols)
    p = save_log(ExperimentLog(cols, lg.meta), tmp_path / "bad.csv")
    with pytest.raises(LogError) as ei:
        load_log(p)
    msg = str(ei.value)
    assert str(p) in msg and f"'{column}'" in msg and words in msg, msg
    assert ei.value.column == column
    if row is not None:
        assert ei.value.row == row and f"row {row}" in msg


def test_non_numeric_cell_names_line(tmp_path):
    lg = _small_log(5)
    p = save_log(lg, tmp_path / "ok.csv")
    lines = p.read_text().splitlines()
    header_i = next(i for i, s in enumerate(lines) if s.startswith("t,"))
    parts = lines[header_i + 3].split(",")
    parts[3] = "abc"
    lines[header_i + 3] = ",".join(parts)
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(LogError, match=r"column 'phi_back_rad', row 3 \(line \d+\).*'abc'"):
        load_log(p)


def test_load_dataset_reports_every_bad_file(tmp_path):
    good = save_log(_small_log(), tmp_path / "a.csv")
    bad1 = _write(tmp_path, "b.csv", "t,x\n0,1\n")
    bad2 = _write(tmp_path, "c.csv.gz", "")
    with pytest.raises(LogError) as ei:
        load_dataset([good, bad1, bad2])
    assert "b.csv" in str(ei.value) and "c.csv.gz" in str(ei.value)
    assert len(load_dataset([good])) == 1
    gz = tmp_path / "d.csv.gz"
    with gzip.open(gz, "wt") as fh:
        fh.write(save_log(_small_log(), tmp_path / "e.csv").read_text())
    assert len(load_dataset([gz])) == 1


def test_pitch_height_columns_alternative(tmp_path):
    n = 40
    lg = _small_log(n)
    cols = {k: v for k, v in lg.columns.items() if not k.startswith("laser_")}
    cols["pitch_rad"] = np.full(n, 0.05)
    cols["height_m"] = np.full(n, 0.3)
    cols["torque_back_nm"] = np.full(n, 1.5)
    cols["torque_front_nm"] = np.full(n, -1.5)
    for c in ("current_back_a", "current_front_a"):
        cols.pop(c)
    back = load_log(save_log(ExperimentLog(cols, {}), tmp_path / "p.csv"))
    np.testing.assert_allclose(back.pitch, 0.05, atol=1e-9)
    np.testing.assert_allclose(back.hip_torque("back"), 1.5)


# -----------------------------------------------------------------------------------------
# CLI
# -----------------------------------------------------------------------------------------
def test_cli_compare_writes_errors_csv(sim_log, tmp_path, capsys):
    from scoutsim.cli import main

    p = save_log(sim_log, tmp_path / "self.csv.gz")
    out = tmp_path / "cmp"
    code = main(
        [
            "compare",
            str(p),
            "--models",
            "II",
            "--out",
            str(out),
            "--no-progress",
            "--friction",
            "0.8",
        ]
    )
    stdout = capsys.readouterr().out
    assert code == 0
    with open(out / "errors.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert tuple(rows[0].keys()) == CSV_COLUMNS
    assert [r["metric"] for r in rows] == list(ERROR_METRICS)
    assert all(r["model"] == "II" for r in rows)
    assert "stride frequency" in stdout and "SYNTHETIC" in stdout
    # compared with itself, the means agree (to the 7 digits the CSV keeps)
    with open(out / "errors_detail.csv") as fh:
        detail = list(csv.DictReader(fh))
    assert all(float(r["percent_error_of_means"]) < 1e-3 for r in detail)  # CSV rounding


def test_cli_compare_bad_log_exits_2(tmp_path, capsys):
    from scoutsim.cli import main

    bad = _write(tmp_path, "bad.csv", "t,x\n0,1\n")
    code = main(["compare", str(bad), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and "bad.csv" in err and "missing column" in err


def test_cli_compare_example(tmp_path, capsys):
    """`scoutsim compare --example` (the Fig. 12 table on the shipped virtual Scout II):
    Model I and Model II both reach a steady stride and have finite mean and max errors in
    all seven metrics, over every experimental stride; the virtual robot has effects
    neither model has, so neither matches it exactly. The paper's claims on these errors
    are tested in tests/test_paper_claims.py."""
    from scoutsim.cli import main

    code = main(
        ["compare", "--example", "--models", "II,I", "--out", str(tmp_path), "--no-progress"]
    )
    stdout = capsys.readouterr().out
    assert code == 0
    assert "SYNTHETIC" in stdout
    with open(tmp_path / "errors.csv") as fh:
        rows = list(csv.DictReader(fh))
    for model in ("I", "II"):
        mine = {r["metric"]: r for r in rows if r["model"] == model}
        assert list(mine) == list(ERROR_METRICS)
        for r in mine.values():
            mean, mx = float(r["mean_percent_error"]), float(r["max_percent_error"])
            assert math.isfinite(mean) and math.isfinite(mx) and 0.0 <= mean <= mx
            assert int(r["n_strides"]) >= 14
        assert float(mine["stride_frequency_hz"]["mean_percent_error"]) > 1.0


def test_missing_column_hints_at_a_misnamed_one(tmp_path):
    lg = _small_log()
    cols = dict(lg.columns)
    cols["phi_back_deg"] = cols.pop("phi_back_rad")
    p = save_log(ExperimentLog(cols, {}), tmp_path / "hint.csv")
    with pytest.raises(LogError, match=r"'phi_back_rad' \(found 'phi_back_deg'"):
        load_log(p)
