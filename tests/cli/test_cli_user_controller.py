"""A user's own controller from the shell: ``--controller MODULE:FACTORY`` in every command
that takes a controller (scoutsim.cli, scoutsim.control.factory).

The test writes a module into a temporary directory, puts it on PYTHONPATH (as a user
would) and runs each command as a separate process, so the module is imported by the
command and by its worker processes alike.
"""

import csv
import json
import os
import subprocess
import sys
import textwrap

import pytest

USER_MODULE = textwrap.dedent('''
    """A researcher's controllers, outside the package."""
    import dataclasses

    import numpy as np

    from scoutsim.control import CompiledController, PitchFeedbackController
    from scoutsim.control import sensors as S

    def table_i(robot, params):
        """The Table I law with a front touchdown angle 5 mrad steeper."""
        return dataclasses.replace(
            params, touchdown_angle_front=params.touchdown_angle_front - 0.005)

    def pitch(robot, params):
        """Table I with torso feedback (a Python controller object)."""
        return PitchFeedbackController(params)

    def hold(t, y, params, state, torque, leg_states):
        for leg in range(2):
            torque[leg] = (params[0] * (params[2 + leg] - y[S.HIP_ANGLE + leg])
                           - params[1] * y[S.HIP_RATE + leg])
        return 0

    def compiled(robot):
        """A compiled PD hold of both hips (it does not bound)."""
        return CompiledController(hold, params=np.array([50.0, 1.0, 0.3, 0.3]))

    def not_a_controller(robot, params):
        return 42

    class Limp:
        """A Python controller that keeps no state it could give (no get_state)."""

        def command(self, t, sensors):
            return (0.0, 0.0)

    def limp(robot, params):
        return Limp()
    ''')


@pytest.fixture(scope="module")
def user_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("user")
    (d / "usermod.py").write_text(USER_MODULE)
    return d


def scoutsim(user_dir, *args, cwd):
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(user_dir)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]
    )
    return subprocess.run(
        [sys.executable, "-m", "scoutsim", *args, "--quiet"],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )


def run_controller(out) -> str:
    """How the saved run's provenance names the controller that ran."""
    from scoutsim import SimulationResult

    return SimulationResult.load(out).provenance["controller_kind"]


def test_run_takes_a_compiled_controller_from_a_module(user_dir, tmp_path):
    """run: the factory's CompiledController runs, and the provenance names it."""
    p = scoutsim(
        user_dir,
        "run",
        "--controller",
        "usermod:compiled",
        "--duration",
        "0.5",
        "--model",
        "I",
        "--out",
        str(tmp_path / "o"),
        cwd=tmp_path,
    )
    assert p.returncode == 0, p.stderr
    assert run_controller(tmp_path / "o") == "hold"


def test_run_takes_a_python_controller_from_a_module(user_dir, tmp_path):
    p = scoutsim(
        user_dir,
        "run",
        "--controller",
        "usermod:pitch",
        "--duration",
        "0.5",
        "--out",
        str(tmp_path / "o"),
        cwd=tmp_path,
    )
    assert p.returncode == 0, p.stderr
    assert "PitchFeedback" in run_controller(tmp_path / "o")


@pytest.mark.parametrize(
    "spec,expected",
    [
        ("nosuchmodule:make", "cannot import module 'nosuchmodule'"),
        ("usermod:nosuch", "has no attribute 'nosuch'"),
        ("usermod:not_a_controller", "returned int, not a controller"),
    ],
)
def test_a_bad_factory_is_a_usage_error(user_dir, tmp_path, spec, expected):
    """An unimportable module, a missing factory or a factory that returns no controller:
    exit 2 and a message saying which, before anything runs."""
    p = scoutsim(
        user_dir,
        "run",
        "--controller",
        spec,
        "--duration",
        "0.5",
        "--out",
        str(tmp_path / "o"),
        cwd=tmp_path,
    )
    assert p.returncode == 2
    assert expected in p.stderr
    assert not (tmp_path / "o" / "summary.json").exists()


def test_basin_runs_a_module_controller_on_two_workers(user_dir, tmp_path):
    """basin with workers: every start runs the user's controller (none is an error of the
    study), and the table equals the one-worker table."""
    tables = {}
    for workers in ("1", "2"):
        out = tmp_path / f"b{workers}"
        p = scoutsim(
            user_dir,
            "basin",
            "--controller",
            "usermod:pitch",
            "--model",
            "ideal",
            "--floors",
            "1",
            "--speeds",
            "1.2,1.4",
            "--pitch-rates",
            "0",
            "--heights",
            "0.33",
            "--duration",
            "1",
            "--workers",
            workers,
            "--no-plots",
            "--out",
            str(out),
            cwd=tmp_path,
        )
        assert p.returncode == 0, p.stderr
        with open(out / "basin.csv") as fh:
            rows = list(csv.DictReader(fh))
        assert rows and all(r["outcome"] != "error" for r in rows), rows
        tables[workers] = rows
    assert tables["1"] == tables["2"]


def test_sweep_runs_a_module_controller_on_two_workers(user_dir, tmp_path):
    tables = {}
    for workers in ("1", "2"):
        out = tmp_path / f"s{workers}"
        p = scoutsim(
            user_dir,
            "sweep",
            "--controller",
            "usermod:compiled",
            "--model",
            "I",
            "--grid",
            "robot.leg_stiffness=3000:3500:2",
            "--duration",
            "0.5",
            "--workers",
            workers,
            "--out",
            str(out),
            cwd=tmp_path,
        )
        assert p.returncode == 0, p.stderr
        with open(out / "sweep.csv") as fh:
            rows = list(csv.DictReader(fh))
        assert len(rows) == 2 and all(r["outcome"] != "error" for r in rows), rows
        tables[workers] = rows
    assert tables["1"] == tables["2"]


def test_a_sweep_of_a_field_the_factory_does_not_read_is_refused(user_dir, tmp_path):
    # 'compiled' holds the hips with gains of its own: a sweep of a touchdown angle would
    # run the same controller at every point and report the flat table as the robot's
    p = scoutsim(
        user_dir,
        "sweep",
        "--controller",
        "usermod:compiled",
        "--grid",
        "controller.touchdown_angle_front_deg=17:19:2",
        "--duration",
        "0.5",
        "--workers",
        "1",
        "--out",
        str(tmp_path / "s"),
        cwd=tmp_path,
    )
    assert p.returncode == 2, p.stderr
    assert "controller.touchdown_angle_front_deg: the factory 'usermod:compiled'" in p.stderr
    assert "does not read touchdown_angle_front" in p.stderr
    assert not (tmp_path / "s" / "sweep.csv").exists()


def test_tune_runs_a_module_controller(user_dir, tmp_path):
    p = scoutsim(
        user_dir,
        "tune",
        "--controller",
        "usermod:table_i",
        "--model",
        "ideal",
        "--param",
        "controller.touchdown_angle_front_deg",
        "--objective",
        "max-speed",
        "--budget",
        "4",
        "--population",
        "4",
        "--duration",
        "1",
        "--workers",
        "2",
        "--out",
        str(tmp_path / "t"),
        cwd=tmp_path,
    )
    assert p.returncode == 0, p.stderr
    with open(tmp_path / "t" / "tune.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 4
    assert all("Error" not in (r.get("error") or "") for r in rows), rows
    # a factory's tuned values are the parameters it was called with: best.json has them,
    # and the command says how to run them, not a controller file of the Table I law
    assert (tmp_path / "t" / "best.json").is_file()
    assert not (tmp_path / "t" / "best.toml").exists()
    assert "best.toml" not in p.stdout
    assert "--controller usermod:table_i --robot FILE" in p.stdout
    assert "controller.touchdown_angle_front_deg: [controller]" in p.stdout


def test_orbit_takes_a_factory_of_table_i_parameters(user_dir, tmp_path):
    """orbit: the factory's parameters are the ones whose orbit is found (its front
    touchdown angle differs from the default orbit's); a controller that does not bound
    is reported (exit 1, the reason), and a Python controller that offers no state of its
    own is refused with the reason (exit 2), by sweep --orbit as well."""
    own = scoutsim(
        user_dir,
        "orbit",
        "--controller",
        "usermod:table_i",
        "--model",
        "ideal",
        "--json",
        cwd=tmp_path,
    )
    assert own.returncode == 0, own.stderr
    default = scoutsim(user_dir, "orbit", "--model", "ideal", "--json", cwd=tmp_path)
    assert default.returncode == 0, default.stderr
    a, b = json.loads(own.stdout), json.loads(default.stdout)
    assert a["residual"] < 1e-9 and b["residual"] < 1e-9
    assert a["touchdown_angle_front_deg"] != b["touchdown_angle_front_deg"]
    still = scoutsim(
        user_dir, "orbit", "--controller", "usermod:compiled", "--duration", "1", cwd=tmp_path
    )
    assert still.returncode == 1 and "lift-off" in still.stderr
    refused = scoutsim(
        user_dir, "orbit", "--controller", "usermod:limp", "--duration", "0.5", cwd=tmp_path
    )
    assert refused.returncode == 2
    assert "get_state" in refused.stderr
    # a Python controller's stride map is differenced: --jacobian exact is refused by name
    inexact = scoutsim(
        user_dir, "orbit", "--controller", "usermod:limp", "--jacobian", "exact", cwd=tmp_path
    )
    assert inexact.returncode == 2
    assert "--jacobian exact" in inexact.stderr and "--jacobian fd" in inexact.stderr
    # a sweep with --orbit refuses it before any point runs (every point would report
    # it), and writes nothing
    swept = scoutsim(
        user_dir,
        "sweep",
        "--controller",
        "usermod:limp",
        "--orbit",
        "--grid",
        "robot.belt_stiffness=300:400:2",
        "--duration",
        "0.5",
        "--out",
        "s",
        cwd=tmp_path,
    )
    assert swept.returncode == 2
    assert "--orbit" in swept.stderr and "get_state" in swept.stderr
    assert not (tmp_path / "s" / "sweep.csv").exists()
