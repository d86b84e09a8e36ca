"""Tests of the experiment-log input checks that keep `scoutsim compare` from being silently
wrong: isolated spikes in the position-like signals (a Hampel test in
scoutsim.validation.log_spikes) and logs that hold no stride (scoutsim.validation.log_strides /
errors.compare and the CLI)."""

import re

import numpy as np
import pytest

from scoutsim import simulate
from scoutsim.state import InitialState
from scoutsim.validation import ExperimentLog, LogError, SensorNoise, load_log, save_log, to_log
from scoutsim.validation.errors import compare
from scoutsim.validation.make_example import example_paths

#: a data row in a steady stride of example_run1 (t = 5 s)
ROW = 5001


@pytest.fixture(scope="module")
def example():
    """The shipped example_run1 (10 s at 1 kHz, synthetic, with sensor noise)."""
    return load_log(example_paths()[0])


def _with(log, rows=None, **values):
    """A copy of ``log`` (rows ``rows``, a slice, if given) with ``column=(row, value)``
    replacements (1-based data rows) or whole replacement columns."""
    cols = {k: v.copy() for k, v in log.columns.items()}
    for c, v in values.items():
        if isinstance(v, tuple):
            row, x = v
            cols[c][row - 1] = x
        else:
            cols[c] = np.asarray(v, dtype=float)
    if rows is not None:
        cols = {k: v[rows] for k, v in cols.items()}
    return ExperimentLog(cols, log.meta)


def _load_error(log, path):
    """The LogError that load_log raises for ``log`` saved to ``path``."""
    save_log(log, path)
    with pytest.raises(LogError) as ei:
        load_log(path)
    return ei.value


def _bounding_log(periods, fs=1000.0, duty_back=0.6):
    """A synthetic log of back-leg lift-off to lift-off strides of the given periods [s]:
    back leg in stance for the first ``duty_back`` of each stride, front leg in the second
    half; smooth torso signals."""
    edges = np.concatenate([[0.0], np.cumsum(periods)])
    t = np.arange(int(round(edges[-1] * fs)) + 1) / fs
    k = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, len(periods) - 1)
    phase = (t - edges[k]) / np.asarray(periods)[k]
    n = t.size
    cols = {
        "t": t,
        "laser_front_m": 0.28 + 0.01 * np.sin(2 * np.pi * phase),
        "laser_back_m": 0.28 - 0.01 * np.sin(2 * np.pi * phase),
        "phi_back_rad": 0.2 * np.sin(2 * np.pi * phase),
        "phi_front_rad": -0.2 * np.sin(2 * np.pi * phase),
        "dphi_back_rad_s": np.zeros(n),
        "dphi_front_rad_s": np.zeros(n),
        "current_back_a": np.zeros(n),
        "current_front_a": np.zeros(n),
        "leg_state_back": (phase < duty_back).astype(float),
        "leg_state_front": (phase >= 0.5).astype(float),
    }
    return ExperimentLog(cols, {"source": "test"})


# -----------------------------------------------------------------------------------------
# isolated spikes
# -----------------------------------------------------------------------------------------
def test_a_single_laser_spike_is_refused_naming_file_column_row_and_median(example, tmp_path):
    # one laser sample replaced by 4.9 m (below the 5 m units check) in a steady stride:
    # before this check it loaded, and moved a Fig. 12 pitch max error from 13 % to 54 %
    p = tmp_path / "spike.csv.gz"
    err = _load_error(_with(example, laser_front_m=(ROW, 4.9)), p)
    msg = str(err)
    v = example.columns["laser_front_m"]
    median = np.median(np.r_[v[ROW - 4 : ROW - 1], v[ROW : ROW + 3]])
    assert err.column == "laser_front_m" and err.row == ROW
    assert str(p) in msg and "column 'laser_front_m'" in msg, msg
    assert re.search(rf"row {ROW} \(line \d+\): value 4\.9 m is an isolated spike", msg), msg
    assert f"median of {median:.6g} m" in msg, msg
    assert "allowed: within 0.02 m of the neighbours' median" in msg, msg
    assert "(1 such sample(s) in the column)" in msg and "fix the sample" in msg, msg
    # the same file without the spike loads
    load_log(save_log(example, tmp_path / "clean.csv.gz"))


@pytest.mark.parametrize(
    "column, delta, refused",
    [
        ("laser_front_m", 0.03, True),  # floor 2 cm
        ("laser_front_m", -0.03, True),
        ("laser_front_m", 0.01, False),
        ("laser_back_m", 0.03, True),
        ("laser_back_m", -0.01, False),
        ("phi_back_rad", 0.15, True),  # floor 0.1 rad
        ("phi_back_rad", 0.05, False),
        ("phi_front_rad", -0.15, True),
        ("leg_length_front_m", 0.03, True),  # floor 2 cm
        ("leg_length_front_m", 0.01, False),
    ],
)
def test_spike_floors_per_column(example, tmp_path, column, delta, refused):
    v = example.columns[column]
    log = _with(example, **{column: (ROW, v[ROW - 1] + delta)})
    p = save_log(log, tmp_path / "x.csv")
    if refused:
        with pytest.raises(LogError) as ei:
            load_log(p)
        assert ei.value.column == column and ei.value.row == ROW, str(ei.value)
    else:
        load_log(p)


def test_pitch_and_height_columns_are_checked(tmp_path):
    n = 2001
    t = np.arange(n) * 1e-3
    rng = np.random.default_rng(0)
    base = _bounding_log([0.25] * 8)
    cols = {k: v[:n] for k, v in base.columns.items() if not k.startswith("laser_")}
    cols["pitch_rad"] = 0.08 * np.sin(2 * np.pi * 4.4 * t) + rng.normal(0, 1e-3, n)
    cols["height_m"] = 0.3 + 0.005 * np.sin(2 * np.pi * 4.4 * t) + rng.normal(0, 1e-3, n)
    log = ExperimentLog(cols, {})
    for column, delta, refused in (
        ("pitch_rad", 0.05, True),
        ("pitch_rad", -0.015, False),
        ("height_m", 0.015, True),
        ("height_m", 0.005, False),
    ):
        bad = _with(log, **{column: (1000, cols[column][999] + delta)})
        p = save_log(bad, tmp_path / f"{column}{delta}.csv")
        if refused:
            with pytest.raises(LogError, match=rf"column '{column}', row 1000 .*isolated spike"):
                load_log(p)
        else:
            load_log(p)


def test_bursts_of_up_to_three_samples_are_spikes_longer_steps_are_not(example, tmp_path):
    v = example.columns["laser_back_m"].copy()
    burst = v.copy()
    burst[ROW - 1 : ROW + 2] = 0.5  # rows ROW..ROW+2
    err = _load_error(_with(example, laser_back_m=burst), tmp_path / "burst.csv")
    assert err.row == ROW and "(3 such sample(s) in the column)" in str(err), str(err)
    # a plateau of 20 samples (something under the beam) and a lasting 5 cm step of the
    # laser, and a 0.3 rad step of a leg angle, are real changes, not isolated samples
    plateau = v.copy()
    plateau[ROW - 1 : ROW + 19] += 0.05
    step = v.copy()
    step[ROW - 1 :] += 0.05
    phi = example.columns["phi_back_rad"].copy()
    phi[ROW - 1 :] += 0.3
    for name, log in (
        ("plateau", _with(example, laser_back_m=plateau)),
        ("step", _with(example, laser_back_m=step)),
        ("phi_step", _with(example, phi_back_rad=phi)),
    ):
        load_log(save_log(log, tmp_path / f"{name}.csv"))


@pytest.mark.parametrize("row", [1, 10001])
def test_spikes_at_the_ends_of_the_record(example, tmp_path, row):
    v = example.columns["laser_front_m"]
    err = _load_error(_with(example, laser_front_m=(row, v[row - 1] + 0.5)), tmp_path / "end.csv")
    assert err.column == "laser_front_m" and err.row == row, str(err)


def test_rates_and_currents_are_not_spike_checked(example, tmp_path):
    # currents follow the controller's commands, which can switch for one control period
    # (a clean Model I simulation has a one-sample 15 A pulse), and rates jump at impacts:
    # a one-sample pulse there is plausible, so it must not refuse the log
    log = _with(
        example,
        current_back_a=(ROW, example.columns["current_back_a"][ROW - 1] + 50.0),
        dphi_front_rad_s=(ROW, example.columns["dphi_front_rad_s"][ROW - 1] + 30.0),
    )
    load_log(save_log(log, tmp_path / "pulse.csv"))


def _worst_spike_ratio(log):
    """Largest |x - neighbours' median| / allowed deviation over the spike-checked columns."""
    from scoutsim.validation.log_spikes import SPIKE_FLOOR, isolated_spikes

    worst = 0.0
    for c, (floor, _) in SPIKE_FLOOR.items():
        if c in log.columns:
            x = log.columns[c]
            flagged, median, allowed = isolated_spikes(x, floor)
            worst = max(worst, float(np.max(np.abs(x - median) / allowed)))
    return worst


def test_example_logs_pass_with_margin(tmp_path):
    from scoutsim.validation.make_example import make_example

    shipped = [load_log(p) for p in example_paths()]
    made = [load_log(p) for p in make_example(tmp_path)]
    for log in shipped + made:
        # every sample within half of its allowed deviation from its neighbours' median
        assert _worst_spike_ratio(log) < 0.5, log.name


@pytest.mark.parametrize("model", ["ideal", "I", "II"])
def test_noisy_simulated_logs_pass(model):
    # three times the default sensor noise (3 mm lasers, 6 mrad angles), two starts, three
    # seeds: the floors leave room for noisier sensors than the example's
    noise = SensorNoise(laser_m=3e-3, angle_rad=6e-3, rate_rad_s=0.15, current_a=0.3)
    for speed in (0.9, 1.4):
        res = simulate(None, None, InitialState(dx=speed), 6.0, model=model)
        for seed in range(3):
            assert _worst_spike_ratio(to_log(res, noise=noise, seed=seed)) < 1.0


# -----------------------------------------------------------------------------------------
# logs without a stride
# -----------------------------------------------------------------------------------------
def _compare_error(log, **kw):
    with pytest.raises(LogError) as ei:
        compare([log], models=("II",), **kw)
    return ei.value


def test_a_03_s_log_is_refused_as_too_short(example, tmp_path):
    p = save_log(_with(example, rows=slice(0, 301)), tmp_path / "short.csv")
    log = load_log(p)  # a valid file ...
    err = _compare_error(log)  # ... but it cannot hold a stride
    msg = str(err)
    assert err.column == "t" and str(p) in msg, msg
    assert "the log lasts 0.300 s (301 samples), too short to hold one steady stride" in msg
    assert (
        "at least 2.3 s plus one stride period (it has no complete stride: 1 back-leg lift-off(s))"
    ) in msg, msg
    assert "--transient" in msg


def test_a_log_with_strides_but_too_short_for_a_steady_one(example):
    log = _with(example, rows=slice(0, 2401))  # 2.4 s: strides, but none steady
    lo = log.liftoff_times("back")
    need = 2.0 + 0.3 + float(np.min(np.diff(lo)))
    err = _compare_error(log)
    assert err.column == "t"
    assert "lasts 2.400 s (2401 samples)" in str(err) and f"= {need:.3f} s" in str(err), str(err)


def test_a_smaller_transient_accepts_a_short_log(example):
    from scoutsim.validation.log_strides import experiment_strides

    log = _with(example, rows=slice(4000, 5501))  # 1.5 s from the steady part
    assert experiment_strides(log, transient_s=0.0).n_steady_strides >= 3
    with pytest.raises(LogError, match="lasts 1.500 s"):
        experiment_strides(log, transient_s=2.0)


def test_a_constant_log_is_refused_no_stride(example, tmp_path):
    n = len(example.t)
    cols = {k: np.full(n, float(np.median(v))) for k, v in example.columns.items()}
    cols["t"] = example.t.copy()
    p = save_log(ExperimentLog(cols, example.meta), tmp_path / "constant.csv")
    err = _compare_error(load_log(p))
    msg = str(err)
    assert err.column == "leg_state_back" and str(p) in msg, msg
    assert "no stride detected in 10.000 s" in msg and "the log has 0" in msg, msg
    assert "leg_state_back is 1 in every row" in msg and "needs at least two" in msg, msg


def test_a_front_leg_that_never_touches_down_is_refused(example):
    err = _compare_error(_with(example, leg_state_front=np.zeros(len(example.t))))
    assert err.column == "leg_state_front"
    assert "the front leg never touches down" in str(err), str(err)


def test_no_steady_stride_in_any_log_is_refused():
    # strides whose period grows by 8 % each: long enough, strides detected, but the gait
    # never settles, so no stride is steady and the table would be empty
    log = _bounding_log(0.15 * 1.08 ** np.arange(22))
    assert log.duration > 5.0 and len(log.liftoff_times("back")) >= 20
    err = _compare_error(log)
    assert "no steady strides in the log (test: 21 strides, none steady)" in str(err), str(err)


def test_a_steady_synthetic_log_passes_the_stride_checks():
    from scoutsim.validation.log_strides import experiment_strides

    g = experiment_strides(_bounding_log([0.25] * 30))
    assert g.n_steady_strides >= 20


@pytest.mark.parametrize(
    "kind, words",
    [
        ("short", "too short to hold one steady stride"),
        ("constant", "no stride detected"),
    ],
)
def test_cli_compare_refuses_with_a_message_and_exit_2(example, tmp_path, capsys, kind, words):
    from scoutsim.cli import main

    if kind == "short":
        log = _with(example, rows=slice(0, 301))
    else:
        log = _with(
            example,
            **{
                k: np.full(len(example.t), float(np.median(v)))
                for k, v in example.columns.items()
                if k != "t"
            },
        )
    p = save_log(log, tmp_path / f"{kind}.csv.gz")
    code = main(
        [
            "compare",
            str(p),
            "--models",
            "II",
            "--out",
            str(tmp_path / "out"),
            "--no-progress",
            "--no-plots",
        ]
    )
    cap = capsys.readouterr()
    assert code == 2, cap
    assert cap.err.startswith(f"scoutsim compare: error: {p}: column '"), cap.err
    assert words in cap.err and "Traceback" not in cap.err, cap.err
    assert cap.out == ""  # no (empty) table
    assert not (tmp_path / "out" / "errors.csv").exists()


def test_repair_spikes_replaces_them_by_the_neighbours_median_and_lists_them(example, tmp_path):
    """load_log(repair_spikes=True): what the refusal suggests, done and reported; the
    repaired log is the clean one but for that sample (its neighbours' median)."""
    p = save_log(
        _with(example, laser_front_m=(ROW, 4.9), phi_back_rad=(ROW + 2000, 1.5)),
        tmp_path / "spikes.csv.gz",
    )
    log = load_log(p, repair_spikes=True)
    clean = load_log(save_log(example, tmp_path / "clean.csv.gz"))
    v = clean.columns["laser_front_m"]
    median = np.median(np.r_[v[ROW - 4 : ROW - 1], v[ROW : ROW + 3]])
    assert [(c, r) for c, r, _, _ in log.repairs] == [
        ("laser_front_m", ROW),
        ("phi_back_rad", ROW + 2000),
    ]
    assert log.repairs[0][2] == 4.9 and log.repairs[0][3] == pytest.approx(median)
    fixed = log.columns["laser_front_m"]
    assert fixed[ROW - 1] == pytest.approx(median)
    assert np.array_equal(np.delete(fixed, ROW - 1), np.delete(v, ROW - 1))
    assert load_log(save_log(example, tmp_path / "again.csv.gz"), repair_spikes=True).repairs == ()


def test_cli_repair_spikes_reports_each_on_stderr(example, tmp_path, capsys):
    from scoutsim.cli import main

    p = save_log(_with(example, laser_front_m=(ROW, 4.9)), tmp_path / "spike.csv.gz")
    assert main(["plot", str(p), "--out", str(tmp_path / "x.png")]) == 2
    assert "--repair-spikes" in capsys.readouterr().err
    assert main(["plot", str(p), "--repair-spikes", "--out", str(tmp_path / "x.png")]) == 0
    err = capsys.readouterr().err
    assert f"column 'laser_front_m', row {ROW}: spike 4.9 replaced by its neighbours' median" in err
