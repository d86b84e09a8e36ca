"""Tests of the command-line interface (scoutsim.cli): exit codes, written files, error
messages, and the basin sweep."""

import csv
import json
import subprocess
import sys

import numpy as np
import pytest

import scoutsim
from scoutsim import SimulationResult
from scoutsim.cli import build_parser, main

FIRST_KEYS = [
    "outcome",
    "mean_speed_m_s",
    "stride_frequency_hz",
    "duty_factor_back",
    "duty_factor_front",
    "pitch_max_deg",
    "pitch_min_deg",
    "height_max_m",
    "height_min_m",
    "max_friction_ratio",
    "n_steady_strides",
]
#: what `scoutsim run` writes by default, and with --plots --csv --npz
DEFAULT_RUN_FILES = ["timeseries.parquet", "events.parquet", "summary.json", "manifest.json"]
RUN_FILES = DEFAULT_RUN_FILES + ["timeseries.csv", "result.npz", "run.png", "torque_speed.png"]


@pytest.fixture(scope="module")
def run_out(tmp_path_factory):
    """One `scoutsim run` shared by the tests that only read its output."""
    out = tmp_path_factory.mktemp("run")
    capture = pytest.MonkeyPatch()
    import io

    buf_out, buf_err = io.StringIO(), io.StringIO()
    capture.setattr(sys, "stdout", buf_out)
    capture.setattr(sys, "stderr", buf_err)
    try:
        code = main(
            [
                "run",
                "--duration",
                "0.5",
                "--model",
                "II",
                "--out",
                str(out),
                "--no-progress",
                "--friction",
                "0.8",
                "--plots",
                "--csv",
                "--npz",
            ]
        )
    finally:
        capture.undo()
    return code, out, buf_out.getvalue(), buf_err.getvalue()


def test_run_exits_0_and_writes_all_files(run_out):
    code, out, stdout, _ = run_out
    assert code == 0
    for name in RUN_FILES:
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    assert (out / "run.png").read_bytes().startswith(b"\x89PNG")


def test_run_prints_a_summary_table(run_out):
    _, _, stdout, _ = run_out
    for text in (
        "outcome",
        "mean forward speed",
        "stride frequency",
        "duty factor",
        "pitch max / min",
        "height max / min",
        "friction ratio",
        "steady strides",
        "real-time factor",
        "compiled core",
        "command wall time",
    ):
        assert text in stdout, text


def test_summary_json_has_the_required_first_keys(run_out):
    _, out, _, _ = run_out
    summary = json.loads((out / "summary.json").read_text())
    assert list(summary)[: len(FIRST_KEYS)] == FIRST_KEYS
    assert summary["outcome"] == "completed"
    assert summary["model"] == "II"


def test_csv_matches_the_saved_result(run_out):
    _, out, _, _ = run_out
    result = SimulationResult.load(out / "result.npz")
    data = np.loadtxt(out / "timeseries.csv", delimiter=",", skiprows=1, ndmin=2)
    assert data.shape == (len(result.t), len(result.columns())) == (501, data.shape[1])
    header = (out / "timeseries.csv").read_text().splitlines()[0].split(",")
    assert header[:4] == ["t [s]", "x [m]", "y [m]", "theta [rad]"]
    assert "hip_torque_applied_back [N m]" in header and "motor_current_front [A]" in header
    assert "leg_state_back" in header
    # the plain CSV reads back bit for bit (17 significant digits)
    for j, (name, column) in enumerate(result.columns().items()):
        np.testing.assert_array_equal(data[:, j], column, err_msg=name)
    # options reach the simulation
    assert result.provenance["friction_coefficient"] == 0.8
    assert result.provenance["model"] == "II"


def test_run_tables_load_back_bit_for_bit(run_out):
    _, out, _, _ = run_out
    npz = SimulationResult.load(out / "result.npz")
    for source in (out, out / "timeseries.parquet"):
        back = SimulationResult.load(source)
        for name in ("t", "state", "aux", "modes", "events", "event_states"):
            np.testing.assert_array_equal(getattr(back, name), getattr(npz, name), err_msg=name)
        assert (back.outcome, back.t_end, back.stats, back.provenance) == (
            npz.outcome,
            npz.t_end,
            npz.stats,
            npz.provenance,
        )


def test_run_writes_only_tables_and_summary_by_default(tmp_path, capsys):
    assert main(["run", "--duration", "0.2", "--out", str(tmp_path), "--no-progress"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(DEFAULT_RUN_FILES)
    assert (
        "wrote timeseries.parquet, events.parquet, summary.json, manifest.json"
        in capsys.readouterr().out
    )


def test_run_csv_format_and_steps(tmp_path):
    out = tmp_path / "csv"
    assert (
        main(
            [
                "run",
                "--duration",
                "0.2",
                "--out",
                str(out),
                "--no-progress",
                "--format",
                "csv",
                "--steps",
            ]
        )
        == 0
    )
    assert sorted(p.name for p in out.iterdir()) == sorted(
        ["timeseries.csv.gz", "events.csv.gz", "steps.csv.gz", "summary.json", "manifest.json"]
    )
    back = SimulationResult.load(out)
    ref = scoutsim.simulate(duration=0.2, record_steps=True, friction_coefficient=1.0)
    for name in ("t", "state", "aux", "modes", "events", "event_states", "steps"):
        np.testing.assert_array_equal(getattr(back, name), getattr(ref, name), err_msg=name)


def test_plot_command_reads_a_run_directory(run_out, tmp_path, capsys):
    _, out, _, _ = run_out
    fig = tmp_path / "fig.png"
    assert main(["plot", str(out), "--out", str(fig)]) == 0
    assert fig.read_bytes().startswith(b"\x89PNG")
    assert main(["plot", str(out / "timeseries.parquet"), "--out", str(fig)]) == 0


def test_console_script_exits_with_its_output_complete(tmp_path):
    """`python -m scoutsim run` ends with os._exit after flushing: every line printed and
    every file written are there."""
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "scoutsim",
            "run",
            "--duration",
            "0.05",
            "--out",
            str(tmp_path),
            "--no-progress",
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.rstrip().endswith(f"to {tmp_path}/")
    assert SimulationResult.load(tmp_path).t[-1] == pytest.approx(0.05)


def test_run_json_prints_the_summary_on_stdout(tmp_path, capsys):
    assert (
        main(
            [
                "run",
                "--duration",
                "0.3",
                "--model",
                "I",
                "--out",
                str(tmp_path),
                "--no-progress",
                "--json",
                "--no-plots",
                "--rtol",
                "1e-7",
            ]
        )
        == 0
    )
    printed = json.loads(capsys.readouterr().out)
    assert printed == json.loads((tmp_path / "summary.json").read_text())
    assert list(printed)[: len(FIRST_KEYS)] == FIRST_KEYS
    assert not (tmp_path / "run.png").exists()
    prov = SimulationResult.load(tmp_path).provenance
    assert prov["integrator"]["rtol"] == 1e-7 and prov["model"] == "I"


@pytest.mark.parametrize(
    "body, field",
    [
        ("[robot]\ntorso_mass = -1.0\n", "torso_mass"),
        ("[robot]\ntorso_mas = 20.0\n", "torso_mas"),
        (
            '[controller]\ntouchdown_angle_front = { value = 21, unit = "kg" }\n',
            "touchdown_angle_front",
        ),
    ],
)
def test_bad_robot_file_exits_2_naming_the_field(tmp_path, capsys, body, field):
    robot = tmp_path / "robot.toml"
    robot.write_text(body)
    code = main(
        [
            "run",
            "--robot",
            str(robot),
            "--duration",
            "0.1",
            "--out",
            str(tmp_path / "out"),
            "--no-progress",
        ]
    )
    err = capsys.readouterr().err
    assert code == 2
    assert field in err and "Traceback" not in err
    assert not (tmp_path / "out" / "summary.json").exists()


def test_missing_or_malformed_robot_file_exits_2(tmp_path, capsys):
    assert main(["run", "--robot", str(tmp_path / "nope.toml"), "--no-progress"]) == 2
    assert "not found" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text("[robot\n")
    assert main(["run", "--robot", str(bad), "--no-progress"]) == 2
    assert "malformed TOML" in capsys.readouterr().err


def test_valid_robot_file_is_used(tmp_path):
    robot = tmp_path / "robot.toml"
    robot.write_text("[robot]\ntorso_mass = 21.5\n[motor]\ncurrent_limit = 10.0\n")
    out = tmp_path / "out"
    assert (
        main(
            [
                "run",
                "--robot",
                str(robot),
                "--duration",
                "0.2",
                "--out",
                str(out),
                "--no-progress",
                "--no-plots",
            ]
        )
        == 0
    )
    prov = SimulationResult.load(out).provenance
    assert prov["robot"]["torso_mass"] == 21.5 and prov["robot"]["current_limit"] == 10.0


def test_usage_errors_exit_2(tmp_path, capsys):
    assert main(["run", "--duration", "-1"]) == 2
    assert main(["run", "--model", "III"]) == 2
    assert main(["basin", "--model", "I,X"]) == 2
    # an initial state with a toe below the ground
    assert (
        main(
            ["run", "--height", "0.2", "--duration", "0.1", "--out", str(tmp_path), "--no-progress"]
        )
        == 2
    )
    assert "below the ground" in capsys.readouterr().err


def test_no_subcommand_prints_help(capsys):
    assert main([]) == 0
    out = capsys.readouterr().out
    assert "usage: scoutsim" in out and "run" in out and "basin" in out


def test_numerical_failure_exits_1_and_still_writes(tmp_path, force_outcome):
    force_outcome("numerical_failure")
    assert (
        main(
            [
                "run",
                "--duration",
                "0.1",
                "--model",
                "I",
                "--out",
                str(tmp_path),
                "--no-progress",
                "--no-plots",
            ]
        )
        == 1
    )
    assert json.loads((tmp_path / "summary.json").read_text())["outcome"] == "numerical_failure"


def test_fall_exits_0_and_summary_says_so(tmp_path, force_outcome, capsys):
    force_outcome("fell")
    assert (
        main(
            [
                "run",
                "--duration",
                "0.1",
                "--model",
                "I",
                "--out",
                str(tmp_path),
                "--no-progress",
                "--no-plots",
            ]
        )
        == 0
    )
    assert "fell at t =" in capsys.readouterr().out


def test_python_dash_m_scoutsim_works():
    proc = subprocess.run(
        [sys.executable, "-m", "scoutsim", "run", "--help"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 0
    assert "--duration" in proc.stdout and "--robot" in proc.stdout


def _read_basin(out):
    with open(out / "basin.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    return rows, json.loads((out / "basin.json").read_text())


def test_basin_writes_one_row_per_start_and_excludes_invalid_starts(tmp_path, capsys):
    out = tmp_path / "basin"
    code = main(
        [
            "basin",
            "--model",
            "I,II",
            "--speeds",
            "1.1",
            "--pitch-rates",
            "-50,0",
            "--heights",
            "0.30,0.36",
            "--duration",
            "0.3",
            "--floors",
            "1.0",
            "--out",
            str(out),
            "--workers",
            "1",
            "--no-progress",
        ]
    )
    assert code == 0
    rows, summary = _read_basin(out)
    assert len(rows) == 2 * 1 * 2 * 2
    assert list(rows[0]) == [
        "model",
        "friction",
        "speed",
        "pitch_rate_deg_s",
        "height",
        "outcome",
        "steady_bounding",
        "mean_speed_m_s",
        "n_steady_strides",
        "status",
        "error",
    ]
    assert sorted({float(r["pitch_rate_deg_s"]) for r in rows}) == [-50.0, 0.0]
    # at 0.30 m a toe starts below the ground (legs at their touchdown angles)
    for r in rows:
        if float(r["height"]) == 0.30:
            assert r["outcome"] == "invalid_start"
        else:
            assert r["outcome"] in ("completed", "fell")
            assert r["steady_bounding"] == "False"  # 0.3 s is far too short
    for m in ("I", "II"):
        s = summary["models"][m]
        assert s["n_starts"] == 4 and s["n_invalid_start"] == 2 and s["n_valid"] == 2
        assert summary["fraction_steady_bounding"][m] == 0.0
    printed = capsys.readouterr().out
    assert "invalid start" in printed and "fraction" in printed


def test_basin_with_a_process_pool_matches_serial(tmp_path):
    args = [
        "basin",
        "--model",
        "I",
        "--speeds",
        "1.0,1.3",
        "--pitch-rates",
        "0",
        "--heights",
        "0.36",
        "--duration",
        "0.3",
        "--no-progress",
        "--friction",
        "1.0",
    ]
    assert main(args + ["--out", str(tmp_path / "a"), "--workers", "2"]) == 0
    assert main(args + ["--out", str(tmp_path / "b"), "--workers", "1"]) == 0
    rows_a, _ = _read_basin(tmp_path / "a")
    rows_b, _ = _read_basin(tmp_path / "b")
    assert len(rows_a) == 2
    assert rows_a == rows_b, "order and values do not depend on the worker count"


def test_basin_rejects_bad_lists():
    assert main(["basin", "--speeds", "1,,2"]) == 2
    assert main(["basin", "--heights", "0.36,-0.1"]) == 2
    assert main(["basin", "--workers", "0"]) == 2


def test_basin_start_that_crashes_is_reported_with_exit_1(tmp_path, monkeypatch, capsys):
    def broken(*args, **kwargs):
        raise RuntimeError("boom")

    monkeypatch.setattr(scoutsim.simulation.simulator, "simulate", broken)
    code = main(
        [
            "basin",
            "--model",
            "I",
            "--speeds",
            "1.1",
            "--pitch-rates",
            "0",
            "--heights",
            "0.36",
            "--duration",
            "0.3",
            "--out",
            str(tmp_path),
            "--workers",
            "1",
            "--no-progress",
            "--floors",
            "inf",
        ]
    )
    assert code == 1
    rows, summary = _read_basin(tmp_path)
    assert [r["outcome"] for r in rows] == ["error"]
    assert "RuntimeError: boom" in capsys.readouterr().err


def test_sweep_cli_grid_in_degrees_writes_table_and_map(
    tmp_path, capsys, monkeypatch, png_draws_each_axes_data
):
    import scoutsim.presentation.plots as plots

    maps = []

    def plot_sweep_map(*args, **kwargs):
        maps.append(real(*args, **kwargs))
        return maps[-1]

    real = plots.plot_sweep_map
    monkeypatch.setattr(plots, "plot_sweep_map", plot_sweep_map)
    out = tmp_path / "sw"
    code = main(
        [
            "sweep",
            "--grid",
            "controller.touchdown_angle_front_deg=19:21:2",
            "--grid",
            "controller.touchdown_angle_back_deg=17:19:2",
            "--model",
            "I",
            "--duration",
            "0.3",
            "--workers",
            "1",
            "--out",
            str(out),
            "--no-progress",
        ]
    )
    assert code == 0
    lines = (out / "sweep.csv").read_text().splitlines()
    assert len(lines) == 1 + 4
    header = lines[0].split(",")
    # a _deg axis is kept in degrees, under its own name (the runs use its radians)
    assert header[0] == "controller.touchdown_angle_front_deg"
    first = dict(zip(header, lines[1].split(",")))
    assert float(first["controller.touchdown_angle_front_deg"]) == 19.0
    assert "[deg]" in maps[0].axes[0].get_xlabel()
    assert "4 points" in capsys.readouterr().out
    assert len(maps) == 1
    png_draws_each_axes_data(out / "map.png", maps[0])


def test_sweep_cli_bad_axis_is_a_usage_error(tmp_path, capsys):
    assert (
        main(["sweep", "--grid", "controller.touchdown_angle_front=1:2", "--out", str(tmp_path)])
        == 2
    )
    assert main(["sweep", "--grid", "robot.torso_mas=1:2:2", "--out", str(tmp_path)]) == 2
    assert "did you mean" in capsys.readouterr().err


@pytest.mark.parametrize("quiet", [False, True])
def test_a_simulating_command_says_it_compiles_unless_quiet(tmp_path, monkeypatch, capsys, quiet):
    """Before the first compilation a simulating command says what it is doing (on stderr,
    so a --json stdout stays clean); --quiet silences it."""
    import scoutsim._numba.jit

    monkeypatch.setattr(scoutsim._numba.jit, "core_is_compiled", lambda: False)
    argv = ["run", "--duration", "0.01", "--no-plots", "--out", str(tmp_path)]
    assert main(argv + (["--quiet"] if quiet else [])) == 0
    err = capsys.readouterr().err
    assert ("compiling" in err) is not quiet


def test_no_compile_notice_when_the_core_is_cached(tmp_path, monkeypatch, capsys):
    import scoutsim._numba.jit

    monkeypatch.setattr(scoutsim._numba.jit, "core_is_compiled", lambda: True)
    assert main(["run", "--duration", "0.01", "--no-plots", "--out", str(tmp_path)]) == 0
    assert "compiling" not in capsys.readouterr().err


def test_progress_messages_go_to_stderr_unless_quiet(monkeypatch, capsys):
    import argparse

    from scoutsim.cli._common import progress_messages

    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    say = progress_messages(argparse.Namespace(no_progress=False, quiet=False), "orbit")
    say("Newton iteration 0")
    err = capsys.readouterr().err
    assert err.startswith("scoutsim orbit [") and err.rstrip().endswith("Newton iteration 0")
    for flags in (dict(no_progress=True, quiet=False), dict(no_progress=False, quiet=True)):
        assert progress_messages(argparse.Namespace(**flags), "orbit") is None


@pytest.mark.parametrize("command", ["run", "basin", "sweep", "compare", "identify", "orbit"])
def test_every_long_command_takes_quiet(command):
    args = build_parser().parse_args(
        [command, "--quiet"] + (["--example"] if command in ("compare", "identify") else [])
    )
    assert args.quiet is True


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--grid", "robot.torso_mass_deg=10:20:2"], "robot.torso_mass' is not an angle"),
        (
            ["--grid", "robot.torso_mass=10:20:2", "--grid", "robot.torso_mass=11:12:2"],
            "robot.torso_mass is given twice",
        ),
        (["--random", "robot.torso_mass=20:10"], "LOW must be below HIGH"),
        (["--random", "robot.torso_mass=10:10"], "LOW must be below HIGH"),
        (
            ["--grid", "robot.torso_mass=1:2:1e9"],
            "the grid has 1e+09 points, more than --max-points",
        ),
        (["--random", "robot.torso_mass=10:20", "--samples", "200001"], "more than --max-points"),
        (["--grid", "robot.torso_mass=inf:2:2"], "finite numbers"),
    ],
)
def test_sweep_refuses_bad_axes_before_starting(argv, message, tmp_path, capsys):
    assert main(["sweep", *argv, "--out", str(tmp_path), "--duration", "0.1"]) == 2
    assert message in capsys.readouterr().err
    assert not any(tmp_path.iterdir())  # nothing was started


def test_sweep_deg_suffix_still_takes_degrees_for_an_angle():
    from scoutsim.cli.sweep import _sweep_axis

    name, vals = _sweep_axis("controller.touchdown_angle_front_deg=15:27:20", 3)
    assert name == "controller.touchdown_angle_front_deg"  # the sweep converts per run
    assert vals == [15.0, 27.0, 20.0]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["run", "--duration", "1e7"], "the run would take about 36.1 h"),
        (
            [
                "sweep",
                "--grid",
                "controller.touchdown_angle_front_deg=15:27:1000",
                "--duration",
                "600",
                "--workers",
                "2",
                "--max-hours",
                "1",
            ],
            "the sweep of 1000 points would take about 1.08 h",
        ),
        (["basin", "--speeds", "1,1.2", "--duration", "1e6"], "the basin map of 36 starts"),
    ],
)
def test_jobs_expected_to_take_too_long_are_refused_before_starting(
    argv, message, tmp_path, capsys
):
    """Simulated time times an upper estimate of the wall time per simulated second
    (Model II 13 ms: 1e7 s -> 36.1 h; 1000 x 600 s on 2 workers -> 1.08 h), against
    --max-hours (default 24)."""
    assert main([*argv, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert message in err and "raise --max-hours" in err
    assert not list(tmp_path.iterdir())  # refused before anything was written


def test_sweep_with_an_unreachable_scheduler_is_a_usage_error_naming_the_timeout(
    tmp_path, monkeypatch, capsys, dask_client_timeouts
):
    """The connection to the scheduler is given SCHEDULER_TIMEOUT_S (not Dask's 30 s) and
    its failure is a usage error naming it, without a traceback."""
    import scoutsim.analysis.parallel as parallel

    monkeypatch.setattr(parallel, "SCHEDULER_TIMEOUT_S", 2.0)
    assert (
        main(
            [
                "sweep",
                "--grid",
                "controller.touchdown_angle_front_deg=19:21:2",
                "--duration",
                "0.2",
                "--scheduler",
                "tcp://127.0.0.1:9",
                "--out",
                str(tmp_path),
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert "no Dask scheduler answered there within 2 s" in err and "Traceback" not in err
    assert dask_client_timeouts == [2.0]


def test_ctrl_c_in_a_basin_map_keeps_the_finished_starts(tmp_path, interrupt_run, capsys):
    """Ctrl-C at the third start (simulate() returns it as interrupted): the two finished
    starts are written to basin.csv, marked partial, exit 130; the cut start is not a row."""
    from scoutsim.io.run_directory import check_run_directory

    interrupt_run(3)
    out = tmp_path / "basin"
    code = main(
        [
            "basin",
            "--model",
            "I",
            "--speeds",
            "1.1,1.2",
            "--pitch-rates",
            "100,150",
            "--heights",
            "0.33",
            "--duration",
            "0.3",
            "--floors",
            "1.0",
            "--out",
            str(out),
            "--workers",
            "1",
            "--no-progress",
        ]
    )
    assert code == 130
    with open(out / "basin.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 2 and all(r["outcome"] != "interrupted" for r in rows)
    manifest = check_run_directory(out)
    assert manifest["status"] == "partial" and list(manifest["files"]) == ["basin.csv"]
    assert "2 of 4 starts are done" in capsys.readouterr().err


def test_run_start_standing_reports_the_startup_duration(tmp_path, capsys):
    assert (
        main(
            [
                "run",
                "--start",
                "standing",
                "--duration",
                "0.6",
                "--model",
                "I",
                "--out",
                str(tmp_path),
                "--no-progress",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "start-up (standing to bounding)" in out
    summary = json.loads((tmp_path / "summary.json").read_text())
    prov = SimulationResult.load(tmp_path).provenance
    assert summary["startup_duration_s"] == prov["startup"]["handover_s"] > 0.2
    assert prov["initial_state"]["kind"] == "standing"


@pytest.mark.parametrize(
    "extra, text",
    [
        (["--speed", "1.0"], "--start flight"),
        (["--model", "passive"], "--model passive"),
    ],
)
def test_run_start_standing_refuses_flight_options_and_the_passive_model(
    tmp_path, capsys, extra, text
):
    code = main(
        [
            "run",
            "--start",
            "standing",
            "--duration",
            "0.1",
            "--out",
            str(tmp_path / "out"),
            "--no-progress",
        ]
        + extra
    )
    err = capsys.readouterr().err
    assert code == 2
    assert text in err and "Traceback" not in err


def test_summary_table_says_when_its_gait_means_are_not_a_steady_bound():
    """A run with a few steady strides that is no steady bound: the table says the gait
    means cover those strides alone; a steady bound's table carries no such line."""
    from scoutsim.cli.run import format_summary

    base = {
        "outcome": "completed",
        "behaviour": "a steady gait with 2 lift-offs per cycle",
        "mean_speed_m_s": 1.45,
        "n_strides": 189,
        "model": "I",
    }
    few = format_summary(
        base | {"n_steady_strides": 1, "steady_bounding": False},
        duration=20.0,
        wall_s=0.3,
        t_end=20.0,
    )
    assert "over 1 steady stride only (not a steady bound)" in few
    bound = format_summary(
        base | {"n_steady_strides": 60, "steady_bounding": True},
        duration=20.0,
        wall_s=0.3,
        t_end=20.0,
    )
    assert "gait means below" not in bound


def test_a_unit_slip_in_a_robot_file_is_warned_of_once_in_one_line(tmp_path, capsys):
    """A leg stiffness written in N/mm (1000x Scout II's) runs, and stderr says once, as
    the command's own line, which field, which file and which slip."""
    import warnings

    robot = tmp_path / "slip.toml"
    robot.write_text('[robot]\nleg_stiffness = { value = 3520, unit = "N/mm" }\n')
    with warnings.catch_warnings():
        warnings.simplefilter("default")
        code = main(
            [
                "run",
                "--robot",
                str(robot),
                "--duration",
                "0.2",
                "--out",
                str(tmp_path / "o"),
                "--quiet",
            ]
        )
    assert code == 0
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if "leg_stiffness" in line]
    assert len(lines) == 1, err
    assert lines[0].startswith("scoutsim run: warning: robot.leg_stiffness")
    assert "N/mm" in lines[0] and "slip.toml" in lines[0]
