"""Every script of examples/ runs as a user runs it: ``python examples/NAME.py --quick``, as a
new process in an empty directory, on a robot whose legs differ (front legs heavier and
stiffer, a front hip unit of lower efficiency and a front amplifier of higher current
limit) for the scripts that take ``--robot``; it exits 0 and produces what its docstring
says. The scripts are found by glob, so a new example is run too (and must accept
``--quick``). Where a script's output states a law, the law is checked: the compiled
example controller reproduces the built-in Table I run bit for bit on that robot (its
per-leg constants packed per leg), the current-estimated torque of the constant-efficiency
transmission is the delivered torque of each leg, the search keeps the best candidate."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

import scoutsim

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SCRIPTS = sorted(EXAMPLES.glob("*.py"))
#: no example takes longer with --quick on a warm cache; a cold one compiles the core first
#: (minutes): a limit against a hung process, not a timing check
TIMEOUT_S = 900

PER_LEG_ROBOT = """\
[robot]
leg_mass = [0.97, 1.12]           # front +15 %
leg_stiffness = [3520.0, 4050.0]  # front +15 %

[transmission]
gearbox_efficiency = [0.68, 0.62]

[motor]
current_limit = [12.0, 13.5]
"""


@pytest.fixture(scope="module")
def robot_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("robot") / "per_leg.toml"
    path.write_text(PER_LEG_ROBOT)
    robot = scoutsim.load_robot(path)
    assert robot.legs_differ and isinstance(robot.leg_mass, tuple)
    return path


def run_example(script: Path, cwd: Path, robot_file: Path, *args: str) -> str:
    """Run ``script --quick`` (with ``--robot robot_file`` if it takes one) in ``cwd``;
    assert it exits 0 and return its standard output."""
    cmd = [sys.executable, str(script), "--quick", *args]
    if "--robot" in script.read_text():
        cmd += ["--robot", str(robot_file)]
    out = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT_S)
    assert out.returncode == 0, (
        f"{' '.join(cmd)} exited {out.returncode}\n"
        f"stdout:\n{out.stdout[-3000:]}\nstderr:\n{out.stderr[-3000:]}"
    )
    return out.stdout


# -- what each script produces --------------------------------------------------------------
def check_compiled_controller(stdout: str, cwd: Path):
    runs = re.findall(r"^(built-in Table I|this example)\s+(\S+)", stdout, re.M)
    assert [name for name, _ in runs] == ["built-in Table I", "this example"], stdout
    assert all(outcome == "completed" for _, outcome in runs), stdout
    # with the pitch-rate gain at 0 the example is the Table I law: packed with each leg's
    # rest length and motor constants, it runs the robot exactly as the built-in controller
    assert "the two runs agree bit for bit: yes" in stdout, stdout


def check_fig10_efficiency(stdout: str, cwd: Path):
    png = cwd / "fig10_efficiency.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    rows = re.findall(
        r"^(constant efficiency|idle \+ load losses)\s+(back|front)\s+(\d+)\s+"
        r"(\S+) N m\s+(\S+) N m$",
        stdout,
        re.M,
    )
    assert len(rows) == 4, stdout
    for run, leg, n_low, _, error in rows:
        assert int(n_low) > 0, (run, leg)
        if run == "constant efficiency":
            # N eta K_T i of each leg's own hip unit is what that transmission delivers
            assert float(error) == 0.0, (run, leg, error)
        else:
            assert float(error) > 0.0, (run, leg, error)
    assert f"wrote {png.name}" in stdout


def check_assumption_study(stdout: str, cwd: Path):
    rows = [line for line in stdout.splitlines() if line.startswith("| ")]
    assert len(rows) >= 10, stdout
    for row in rows:
        fractions = re.findall(r"\| (ideal|I|II): (\d\.\d\d) \(", row)
        assert fractions, row
        assert all(0.0 <= float(f) <= 1.0 for _, f in fractions), row


def check_transfer_study(stdout: str, cwd: Path):
    out = cwd / "transfer_out"
    table = (out / "transfer.md").read_text().splitlines()
    assert table[0].startswith("| controller | trained on |") and len(table) >= 4, table
    rows = json.loads((out / "transfer.json").read_text())
    kinds = {key.split("|")[0] for key in rows}
    assert kinds == {"tuned", "learned"}, sorted(rows)
    for key, row in rows.items():
        assert 0.0 <= row["basin"] <= 1.0, (key, row)
        assert row["outcome"] in ("completed", "fell"), (key, row)
        assert row["trained"]["values"], (key, row)


def check_tune_setpoints(stdout: str, cwd: Path):
    start = re.search(r"^start: .* return (-?[\d.]+),", stdout, re.M)
    best = re.search(r"^best: touchdown angles .* return (-?[\d.]+)$", stdout, re.M)
    assert start and best, stdout
    assert float(best.group(1)) >= float(start.group(1))


CHECKS = {name[len("check_") :]: f for name, f in globals().items() if name.startswith("check_")}


def test_every_check_is_of_an_example():
    assert set(CHECKS) <= {p.stem for p in SCRIPTS}, sorted(CHECKS)


@pytest.mark.parametrize("script", SCRIPTS, ids=[p.stem for p in SCRIPTS])
def test_example_runs_quick_on_a_per_leg_robot(script, robot_file, tmp_path):
    stdout = run_example(script, tmp_path, robot_file)
    assert stdout.strip(), f"{script.name} printed nothing"
    check = CHECKS.get(script.stem)
    if check is not None:
        check(stdout, tmp_path)


def test_every_example_says_how_to_run_it_and_its_quick_mode():
    for script in SCRIPTS:
        doc = script.read_text().split('"""')[1]
        assert f"python examples/{script.name}" in doc, script.name
        assert "--quick" in doc, script.name
