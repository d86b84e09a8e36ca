"""``scoutsim uncertainty``: the same study gives the same indices.csv, byte for byte, on one
worker, two local worker processes and a local Dask cluster, and after an interruption
(Ctrl-C reaching a run) and a rerun of the same command; its outputs and its usage
errors."""

import json

import pytest

from scoutsim.cli import main

#: a tiny study: 2 parameters, N = 8 (32 runs of Model I, 4.5 s: past the 2 s transient
#: the gait metrics skip, long enough that some samples bound steadily and some not)
ARGS = [
    "uncertainty",
    "--model",
    "I",
    "--duration",
    "4.5",
    "--samples",
    "8",
    "--param",
    "controller.touchdown_angle_front_deg=20:22",
    "--param",
    "robot.leg_stiffness=3000:3800",
    "--no-progress",
    "--quiet",
]


def _run(out, *extra) -> int:
    return main([*ARGS, "--out", str(out), *extra])


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("one_worker")
    assert _run(out, "--workers", "1", "--no-plots") == 0
    return out


def test_the_study_writes_its_tables_and_figures(tmp_path, reference):
    assert _run(tmp_path, "--workers", "1") == 0
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert manifest["status"] == "complete"
    assert {"samples.parquet", "indices.csv", "summary.json", "indices.png"} <= set(
        manifest["files"]
    )
    assert (tmp_path / "indices.csv").read_bytes() == (reference / "indices.csv").read_bytes()
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["n_runs"] == 8 * (2 + 2)
    assert sum(summary["outcomes"].values()) == summary["n_runs"]
    bounding = summary["metrics"]["bounds"]["mean"]
    assert summary["share_not_bounding"] == pytest.approx(1 - bounding)
    import pyarrow.parquet as pq

    table = pq.read_table(tmp_path / "samples.parquet").to_pydict()
    assert len(table["sample"]) == summary["n_runs"]
    assert table["block"][:8] == ["A"] * 8 and table["block"][-1] == "AB:robot.leg_stiffness"
    # an AB row takes its own parameter from B and the other from A
    n = 8
    for i in range(n):
        ab = 2 * n + i  # AB_1: the touchdown angle from B
        assert (
            table["controller.touchdown_angle_front_deg"][ab]
            == table["controller.touchdown_angle_front_deg"][n + i]
        )
        assert table["robot.leg_stiffness"][ab] == table["robot.leg_stiffness"][i]


def test_two_workers_give_the_same_indices(tmp_path, reference):
    assert _run(tmp_path, "--workers", "2", "--no-plots") == 0
    assert (tmp_path / "indices.csv").read_bytes() == (reference / "indices.csv").read_bytes()


def test_a_local_dask_cluster_gives_the_same_indices(tmp_path, reference, dask_cluster):
    assert _run(tmp_path, "--scheduler", dask_cluster.scheduler_address, "--no-plots") == 0
    assert (tmp_path / "indices.csv").read_bytes() == (reference / "indices.csv").read_bytes()


def test_an_interrupted_study_run_again_gives_the_same_indices(tmp_path, reference, interrupt_run):
    """Ctrl-C reaching the 5th run: the command exits with 130 and keeps the 4 finished
    runs (and no table); the same command again runs the rest and writes the indices of
    an uninterrupted study."""
    interrupt_run(5)
    assert _run(tmp_path, "--workers", "1", "--no-plots") == 130
    assert len((tmp_path / "points.jsonl").read_text().splitlines()) == 4
    assert not (tmp_path / "indices.csv").exists()
    assert _run(tmp_path, "--workers", "1", "--no-plots") == 0
    assert (tmp_path / "indices.csv").read_bytes() == (reference / "indices.csv").read_bytes()
    assert (tmp_path / "samples.parquet").read_bytes() == (
        reference / "samples.parquet"
    ).read_bytes()


@pytest.mark.parametrize(
    "extra,words",
    [
        ([], "give uncertain parameters"),
        (["--param", "robot.leg_stiffness=-1:2"], "robot.leg_stiffness: low = -1"),
        (["--param", "robot.leg_stiffness=1:2", "--samples", "6"], "a power of two"),
    ],
)
def test_usage_errors_name_what_is_wrong(tmp_path, capsys, extra, words):
    code = main(["uncertainty", "--out", str(tmp_path), "--quiet", *extra])
    assert code == 2
    assert words in capsys.readouterr().err
