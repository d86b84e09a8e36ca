"""A user's own controllers in the parallel studies (basin map, sweep, tuning).

A compiled controller and a Python controller defined in the user's own module (written
here into a temporary directory on sys.path and PYTHONPATH), given as objects or named as
``MODULE:FACTORY``, give on two local worker processes and on a Dask cluster the same
table as in one process, number for number, a sweep's periodic orbits included; the law
they run is Table I's, so their basin map equals the built-in controller's (a check
independent of the parallel machinery). A controller that cannot be sent to a worker (a
closure) is refused before any point runs; a point the study could not run is an error
of the study (StudyError, or a row with status "error" counted apart), never a start that
did not bound nor a bounding point without an orbit."""

import dataclasses
import json
import math
import sys

import pytest

import scoutsim
from scoutsim.analysis import basin as B
from scoutsim.analysis import sweep as SW
from scoutsim.analysis.controlled_orbit import controlled_fixed_point
from scoutsim.analysis.orbit_sensitivity import orbit_sensitivities
from scoutsim.analysis.parallel import NotSendableError
from scoutsim.analysis.study_failures import StudyError
from scoutsim.control import CompiledController
from scoutsim.control.factory import ControllerSpec

USER_MODULE = "scoutsim_user_controllers"
USER_SOURCE = '"""A user\'s controllers, in a module of their own (written by the test)."""\nimport numpy as np\n\nfrom scoutsim.control import CompiledController\nfrom scoutsim.control import sensors as S\n\nTD, SWEEP = 0, 2                      # touchdown angles, sweep limits [rad] (back, front)\nKP, KD, KPB, KDB, TDC, LOC, L0, STALL, SLOPE, TMAX = range(4, 14)\nN = 14\nFLIGHT, RETRACTION, BRAKE = 0, 1, 2\n\n\ndef bound(t, y, p, state, torque, leg_states):\n    """Table I\'s structure written by a user: flight servo, retraction, brake."""\n    for leg in range(2):\n        angle = y[S.HIP_ANGLE + leg]\n        rate = y[S.HIP_RATE + leg]\n        compression = p[L0] - y[S.LEG_LENGTH + leg]\n        st = leg_states[leg]\n        if st == FLIGHT and compression > p[TDC]:\n            st = RETRACTION\n        elif st != FLIGHT and compression < p[LOC]:\n            st = FLIGHT\n        if st == RETRACTION and angle < p[SWEEP + leg]:\n            st = BRAKE\n        leg_states[leg] = st\n        if st == FLIGHT:\n            torque[leg] = p[KP] * (p[TD + leg] - angle) - p[KD] * rate\n        elif st == RETRACTION:\n            torque[leg] = min(0.0, max(-p[STALL] + p[SLOPE] * rate, -p[TMAX]))\n        else:\n            torque[leg] = p[KPB] * (p[SWEEP + leg] - angle) - p[KDB] * rate\n    return 0\n\n\ndef params_of(robot, c):\n    p = np.zeros(N)\n    p[TD:TD + 2] = c.touchdown_angle_back, c.touchdown_angle_front\n    p[SWEEP:SWEEP + 2] = c.sweep_limit_back, c.sweep_limit_front\n    p[KP], p[KD], p[KPB], p[KDB] = c.flight_kp_back, c.flight_kd_back, c.brake_kp_back, c.brake_kd_back\n    p[TDC], p[LOC] = c.touchdown_compression, c.liftoff_compression\n    p[L0], p[STALL], p[SLOPE], p[TMAX] = (robot.leg_rest_length, robot.stall_torque,\n                                          -robot.torque_speed_slope, robot.max_leg_torque)\n    return p\n\n\nclass PyBound:\n    """The same law as a Python controller (command(t, sensors)), its leg states as its\n    own state (get_state / set_state: what the periodic orbits restart strides from)."""\n\n    control_period = 1e-3\n\n    def __init__(self, p, controller_parameters=None):\n        self.p = np.array(p, dtype=float)\n        self.controller_parameters = controller_parameters\n        self.leg_states = np.zeros(2, dtype=np.int64)\n\n    def reset(self, robot, sensors):\n        self.leg_states[:] = 0\n\n    def get_state(self):\n        return tuple(float(v) for v in self.leg_states)\n\n    def set_state(self, values):\n        self.leg_states[:] = np.round(values).astype(np.int64)\n\n    def command(self, t, sensors):\n        torque = np.zeros(2)\n        bound(t, sensors.vector, self.p, None, torque, self.leg_states)\n        return float(torque[0]), float(torque[1])\n\n\ndef make_compiled(robot, params):\n    c = CompiledController(bound, params=params_of(robot, params), name="user_bound")\n    c.controller_parameters = params    # (legs start at the touchdown angles)\n    return c\n\n\ndef make_python(robot, params):\n    return PyBound(params_of(robot, params), params)\n\n\ndef make_broken(robot, params):\n    """A factory with a bug."""\n    raise RuntimeError("the factory\'s own bug")\n\n\nclass Raises(PyBound):\n    """A Python controller whose command has a bug (an AttributeError)."""\n\n    def command(self, t, sensors):\n        return sensors.no_such_reading, 0.0\n\n\nclass GivesUp(PyBound):\n    """A Python controller that returns torques that are not finite after 0.2 s."""\n\n    def command(self, t, sensors):\n        tau = super().command(t, sensors)\n        return (float("nan"), tau[1]) if t >= 0.2 else tau\n\n\ndef make_raises(robot, params):\n    return Raises(params_of(robot, params), params)\n\n\ndef make_gives_up(robot, params):\n    return GivesUp(params_of(robot, params), params)\n\n\nclass Forgets(PyBound):\n    """A Python controller with a bug only a restart from a state reaches: set_state\n    forgets the sample counter its command needs (a run from the start never calls it)."""\n\n    def reset(self, robot, sensors):\n        super().reset(robot, sensors)\n        self.samples = 0\n\n    def set_state(self, values):\n        super().set_state(values)\n        self.samples = None\n\n    def command(self, t, sensors):\n        self.samples += 1\n        return super().command(t, sensors)\n\n\ndef make_forgets(robot, params):\n    return Forgets(params_of(robot, params), params)\n'

# a factory that makes its controller from Table I's defaults whatever it is given (a
# user's slip: the study would run one controller at every point)
USER_SOURCE += (
    "\n\ndef make_fixed(robot, params):\n"
    "    from scoutsim import ControllerParameters\n\n"
    "    return CompiledController(bound, params=params_of(robot, ControllerParameters()),"
    " name='user_fixed')\n"
)

#: two starts from which the Table I law bounds steadily within 6 s
GRID = dict(
    models=("II",),
    speeds=(1.0, 1.3),
    pitch_rates=(math.radians(100.0),),
    heights=(0.36,),
    duration=6.0,
)
KINDS = ["compiled", "python", "factory:make_compiled", "factory:make_python"]


@pytest.fixture(scope="module")
def user(tmp_path_factory):
    """The user's module, importable here and in every worker process started after."""
    import importlib
    import os

    where = tmp_path_factory.mktemp("user")
    (where / f"{USER_MODULE}.py").write_text(USER_SOURCE)
    with pytest.MonkeyPatch.context() as mp:
        mp.syspath_prepend(str(where))
        mp.setenv(
            "PYTHONPATH",
            os.pathsep.join([str(where)] + [p for p in [os.environ.get("PYTHONPATH")] if p]),
        )
        yield importlib.import_module(USER_MODULE)
        sys.modules.pop(USER_MODULE, None)


@pytest.fixture(scope="module")
def dask_client(user):
    """A local Dask cluster of two worker processes (started after the user's module is on
    PYTHONPATH), shared by the tests of this module."""
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        yield client


def _controller(user, kind):
    robot, cparams = scoutsim.RobotParameters(), scoutsim.ControllerParameters()
    if kind == "compiled":
        return user.make_compiled(robot, cparams)
    if kind == "python":
        return user.make_python(robot, cparams)
    return f"{USER_MODULE}:{kind.partition(':')[2]}"


def _same(a, b):
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


@pytest.mark.parametrize("kind", KINDS)
def test_basin_map_of_a_users_controller_is_the_same_on_workers_and_on_dask(
    user, dask_client, kind
):
    """workers=2 and a Dask cluster give the rows of one process; the user's Table I law
    bounds from the starts the built-in Table I controller bounds from."""
    c = _controller(user, kind)
    one = B.basin_of_attraction(controller=c, workers=1, **GRID)
    two = B.basin_of_attraction(controller=c, workers=2, **GRID)
    dask = B.basin_of_attraction(controller=c, scheduler=dask_client, **GRID)
    builtin = B.basin_of_attraction(controller=None, workers=1, **GRID)
    assert [r["status"] for r in one.rows] == ["ok", "ok"]
    assert two.rows == one.rows and dask.rows == one.rows
    assert one.rows == builtin.rows
    assert one.fraction("II") == two.fraction("II") == dask.fraction("II") == 1.0


@pytest.mark.parametrize("kind", KINDS)
def test_sweep_of_a_users_controller_is_the_same_on_workers_and_on_dask(user, dask_client, kind):
    """A controller object is swept over a robot field; a factory over a controller field
    in degrees, which it receives (its table equals the built-in law's)."""
    c = _controller(user, kind)
    if kind.startswith("factory"):
        points = SW.grid_points({"controller.touchdown_angle_front_deg": [19.0, 23.0]})
    else:
        points = SW.grid_points({"robot.leg_damping": [50.0, 60.0]})
    kw = dict(model="II", duration=1.5, controller=c)
    one = SW.sweep(points, workers=1, **kw)
    two = SW.sweep(points, workers=2, **kw)
    dask = SW.sweep(points, scheduler=dask_client, **kw)
    assert [r["status"] for r in one.rows] == ["ok", "ok"]
    assert _same(two.rows, one.rows) and _same(dask.rows, one.rows)
    assert one.rows[0]["average_speed_m_s"] != one.rows[1]["average_speed_m_s"]
    builtin = SW.sweep(points, workers=1, model="II", duration=1.5)
    assert _same(one.rows, builtin.rows)


@pytest.mark.parametrize("kind", KINDS)
def test_tuning_a_users_controller_is_the_same_on_workers_and_on_dask(user, dask_client, kind):
    """One generation of four candidates: the same evaluations everywhere."""
    pytest.importorskip("cmaes")
    from scoutsim.analysis.tune import tune

    c = _controller(user, kind)
    name = {
        "compiled": f"controller.params[{user.TD + 1}]=0.30:0.45",
        "python": "robot.leg_damping=40:70",
    }.get(kind, "controller.touchdown_angle_front_deg")
    kw = dict(controller=c, target=1.3, duration=1.0, population=4, budget=4)
    one = tune([name], workers=1, **kw)
    two = tune([name], workers=2, **kw)
    dask = tune([name], scheduler=dask_client, **kw)
    assert {r["status"] for r in one.rows} == {"ok"}
    assert len({r[name.partition("=")[0]] for r in one.rows}) == 4
    assert _same(two.rows, one.rows) and _same(dask.rows, one.rows)


def test_a_controller_spec_built_in_the_worker_gets_the_studys_robot(user, dask_client):
    """ControllerSpec objects (what the command line passes) run like the string."""
    spec = ControllerSpec(
        f"{USER_MODULE}:make_compiled", scoutsim.RobotParameters(), scoutsim.ControllerParameters()
    )
    one = B.basin_of_attraction(controller=spec, workers=1, **GRID)
    two = B.basin_of_attraction(controller=spec, workers=2, **GRID)
    dask = B.basin_of_attraction(controller=spec, scheduler=dask_client, **GRID)
    assert one.rows == two.rows == dask.rows
    assert one.settings["controller"] == f"{USER_MODULE}:make_compiled"


# -----------------------------------------------------------------------------------------
# controllers that cannot be sent
# -----------------------------------------------------------------------------------------
def _closure_controller(user):
    import numba

    law = numba.njit(user.bound)

    def local_bound(t, y, p, state, torque, leg_states):
        return law(t, y, p, state, torque, leg_states)

    return CompiledController(
        local_bound,
        params=user.params_of(scoutsim.RobotParameters(), scoutsim.ControllerParameters()),
        name="local_bound",
    )


def _local_class_controller(user):
    class Local(user.PyBound):
        pass

    return Local(user.params_of(scoutsim.RobotParameters(), scoutsim.ControllerParameters()))


@pytest.fixture
def no_point_runs(monkeypatch):
    """Every study's map of its points, recorded: what ran."""
    calls = []

    def map_tasks(*args, **kwargs):
        calls.append(args)
        raise AssertionError("a point was sent to run")

    from scoutsim.analysis import sweep_checkpoint, tune

    # (the sweep maps its points through its checkpoint's map_with_checkpoint)
    for module in (B, sweep_checkpoint, tune):
        monkeypatch.setattr(module, "map_tasks", map_tasks)
    return calls


@pytest.mark.parametrize(
    "make, why",
    [
        (_closure_controller, "defined inside a function"),
        (_local_class_controller, "defined inside a function"),
    ],
)
def test_a_controller_that_cannot_be_sent_is_refused_before_any_point(
    user, make, why, no_point_runs, tmp_path
):
    pytest.importorskip("cmaes")
    from scoutsim.analysis.tune import tune

    c = make(user)
    runs = [
        lambda: B.basin_of_attraction(controller=c, workers=2, **GRID),
        lambda: SW.sweep(
            SW.grid_points({"robot.leg_damping": [50.0, 60.0]}),
            controller=c,
            workers=2,
            duration=1.0,
            out=tmp_path / "sw",
        ),
        lambda: tune(
            ["robot.leg_damping=40:70"],
            controller=c,
            target=1.3,
            duration=1.0,
            population=4,
            budget=4,
            workers=2,
        ),
    ]
    for run in runs:
        with pytest.raises(NotSendableError) as info:
            run()
        text = str(info.value)
        assert scoutsim.control.protocol.controller_name(c) in text
        assert why in text and "workers=1" in text and "MODULE:FACTORY" in text
    assert no_point_runs == []
    assert (
        not (tmp_path / "sw" / SW.CHECKPOINT).exists()
        or (tmp_path / "sw" / SW.CHECKPOINT).read_text() == ""
    )


def test_a_controller_that_cannot_be_sent_runs_in_one_process(user):
    """workers=1 is the way out the message offers: the closure runs, as Table I does."""
    one = B.basin_of_attraction(controller=_closure_controller(user), workers=1, **GRID)
    assert one.rows == B.basin_of_attraction(controller=None, workers=1, **GRID).rows


# -----------------------------------------------------------------------------------------
# errors of the study
# -----------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "factory, words", [("make_broken", "the factory's own bug"), ("make_raises", "no_such_reading")]
)
@pytest.mark.parametrize("workers", [1, 2])
def test_a_point_the_study_cannot_run_is_an_error_not_a_start_that_did_not_bound(
    user, factory, words, workers
):
    """A factory that raises, a controller whose code raises: StudyError by default; with
    on_error="record" rows with status "error", counted apart and left out of the
    fraction (None: no valid start), with a warning."""
    c = f"{USER_MODULE}:{factory}"
    with pytest.raises(StudyError, match=words) as info:
        B.basin_of_attraction(controller=c, workers=workers, **GRID)
    assert info.value.errors and all(r["status"] == "error" for r in info.value.errors)
    with pytest.warns(RuntimeWarning, match="could not be run"):
        res = B.basin_of_attraction(controller=c, workers=workers, on_error="record", **GRID)
    assert [r["status"] for r in res.rows] == ["error", "error"]
    assert res.fraction("II") is None
    (s,) = res.summary().values()
    assert s["n_errors"] == 2 and s["n_valid"] == 0 and s["fraction_steady_bounding"] is None
    points = SW.grid_points({"robot.leg_damping": [50.0, 60.0]})
    with pytest.raises(StudyError, match=words):
        SW.sweep(points, controller=c, workers=workers, duration=1.0)
    with pytest.warns(RuntimeWarning, match="could not be run"):
        res = SW.sweep(points, controller=c, workers=workers, duration=1.0, on_error="record")
    assert [r["status"] for r in res.rows] == ["error", "error"]
    assert res.settings["n_errors"] == 2 and len(res.errors()) == 2


def test_an_evaluation_the_tuning_cannot_run_stops_it_or_is_recorded_apart(user, tmp_path):
    """A controller whose code raises: StudyError after its generation, nothing of it in
    the checkpoint; recorded, it scores as infeasible and is counted apart."""
    pytest.importorskip("cmaes")
    from scoutsim.analysis.tune import EVALUATIONS, tune

    kw = dict(
        controller=f"{USER_MODULE}:make_raises",
        target=1.3,
        duration=0.5,
        population=4,
        budget=4,
        workers=1,
    )
    with pytest.raises(StudyError, match="no_such_reading"):
        tune(["controller.touchdown_angle_front_deg"], out=tmp_path, **kw)
    assert (tmp_path / EVALUATIONS).read_text() == ""
    with pytest.warns(RuntimeWarning, match="could not be run"):
        res = tune(["controller.touchdown_angle_front_deg"], on_error="record", **kw)
    assert res.n_errors == 4 and {r["status"] for r in res.rows} == {"error"}
    assert not any(r["feasible"] for r in res.rows)


def test_a_controller_that_gives_up_did_not_bound(user):
    """Torques that are not finite stop the run: the controller's own failure, a start
    that did not bound (status ok), not an error of the study."""
    res = B.basin_of_attraction(controller=f"{USER_MODULE}:make_gives_up", workers=1, **GRID)
    assert [(r["status"], r["outcome"]) for r in res.rows] == [("ok", "controller_error")] * 2
    (s,) = res.summary().values()
    assert res.fraction("II") == 0.0 and s["n_errors"] == 0 and s["n_valid"] == 2


def test_a_factory_that_cannot_be_imported_is_refused_before_any_point(no_point_runs):
    from scoutsim.control.factory import FactoryError

    with pytest.raises(FactoryError, match="no_such_module_here"):
        B.basin_of_attraction(controller="no_such_module_here:make", workers=2, **GRID)
    assert no_point_runs == []


def test_a_study_of_a_field_the_factory_does_not_read_is_refused_before_any_point(
    user, no_point_runs, tmp_path
):
    """A factory that makes the same controller at both ends of a study's range of a
    controller field: the sweep, the tuning and the uncertainty study would vary nothing
    and report it as the robot's answer; each refuses it, naming the field, before any
    point runs. A factory that reads the field is not refused (the check only builds
    and compares the controllers: the points are refused by the map that follows)."""
    from scoutsim.analysis.tune import tune
    from scoutsim.analysis.uncertainty import parse_parameter, uncertainty_study
    from scoutsim.control.factory import FactoryError

    name = "controller.touchdown_angle_front_deg"
    fixed = f"{USER_MODULE}:make_fixed"
    points = SW.grid_points({name: [19.0, 23.0]})
    match = f"{name}: the factory '{fixed}' makes the same controller"
    with pytest.raises(FactoryError, match=match):
        SW.sweep(points, controller=fixed, duration=0.5, workers=1)
    with pytest.raises(FactoryError, match=match):
        uncertainty_study([parse_parameter(f"{name}=19:23")], n=2, controller=fixed, duration=0.5, workers=1,
                          out=tmp_path / "u")  # fmt: skip
    assert no_point_runs == []
    # the same study with a factory that reads the field passes the check: its points
    # reach the map (here refused by the fixture, which records them)
    with pytest.raises(AssertionError, match="a point was sent to run"):
        SW.sweep(points, controller=f"{USER_MODULE}:make_compiled", duration=0.5, workers=1)
    assert len(no_point_runs) == 1
    pytest.importorskip("cmaes")  # (the tuning's optional dependency)
    with pytest.raises(FactoryError, match=match):
        tune([name], controller=fixed, target=1.3, duration=0.5, budget=4, workers=1)
    assert len(no_point_runs) == 1


def test_basin_pitch_rates_are_si_and_the_older_degree_keyword_still_works():
    """basin_of_attraction takes pitch_rates [rad/s] (the command line's --pitch-rates is in
    deg/s, converted once at the edge); the older pitch_rates_deg_s gives the same rows,
    with a DeprecationWarning; the rows give the rate in deg/s."""
    from scoutsim.analysis.basin import basin_of_attraction

    kw = dict(models=("ideal",), speeds=(1.2,), heights=(0.33,), duration=0.3, workers=1)
    si = basin_of_attraction(pitch_rates=(math.radians(150.0),), **kw)
    with pytest.warns(DeprecationWarning, match="pitch_rates"):
        old = basin_of_attraction(pitch_rates_deg_s=(150.0,), **kw)
    assert si.rows == old.rows
    assert si.rows[0]["pitch_rate_deg_s"] == 150.0


#: two points at which the Table I law settles within 6 s onto orbits of one stride
#: (0.254 s and 0.248 s)
ORBIT_POINTS = SW.grid_points(
    {"robot.belt_stiffness": [200.0, 350.0], "controller.touchdown_angle_front_deg": [23.0]}
)


def test_orbit_sweep_of_a_users_controller_is_the_same_on_workers_and_on_dask(user, dask_client):
    """sweep(orbit=True) with a user's factory: the Python one on two local workers and on
    a Dask cluster, the compiled one on a Dask cluster, find the orbits one process finds
    (period, strides, spectral radius, residual), number for number; the law's two forms
    have the same orbits (the compiled one's Jacobian carried with the run, the Python
    one's by differences: the same multipliers to their accuracy). (The compiled one on
    two local workers is left out: it costs a compilation in each new worker, and its runs
    there are checked above.)"""
    kw = dict(model="II", duration=6.0, orbit=True)
    python = f"{USER_MODULE}:make_python"
    compiled = f"{USER_MODULE}:make_compiled"
    one = SW.sweep(ORBIT_POINTS, workers=1, controller=python, **kw)
    assert [r["orbit_status"] for r in one.rows] == ["ok", "ok"]
    assert [r["orbit_strides"] for r in one.rows] == [1, 1]
    assert [round(r["orbit_period_s"], 6) for r in one.rows] == [0.254, 0.248]
    assert all(r["orbit_stable"] for r in one.rows)
    two = SW.sweep(ORBIT_POINTS, workers=2, controller=python, **kw)
    assert _same(two.rows, one.rows)
    dask = SW.sweep(ORBIT_POINTS[:1], scheduler=dask_client, controller=python, **kw)
    assert _same(dask.rows, one.rows[:1])
    here = SW.sweep(ORBIT_POINTS[:1], workers=1, controller=compiled, **kw)
    dask = SW.sweep(ORBIT_POINTS[:1], scheduler=dask_client, controller=compiled, **kw)
    assert _same(dask.rows, here.rows)
    a, b = here.rows[0], one.rows[0]
    assert (a["orbit_period_s"], a["orbit_strides"]) == (b["orbit_period_s"], b["orbit_strides"])
    radius = "orbit_spectral_radius_per_stride"
    assert abs(a[radius] - b[radius]) < 1e-3


def test_a_controller_bug_in_the_orbit_search_is_an_error_of_the_sweep(user, dask_client):
    """A Python controller whose command raises only in a stride restarted from a section
    state (its set_state's bug): its runs bound, but its orbit search fails in the user's
    code, so with orbit=True each point is an error of the sweep naming the controller's
    exception, in one process and on Dask alike, never a bounding point without an orbit."""
    kw = dict(model="II", duration=6.0, controller=f"{USER_MODULE}:make_forgets")
    runs = SW.sweep(ORBIT_POINTS, workers=1, **kw)
    assert [(r["status"], r["steady_bounding"]) for r in runs.rows] == [("ok", True)] * 2
    for where in ({"workers": 1}, {"scheduler": dask_client}):
        with pytest.warns(RuntimeWarning, match="2 of its 2 points could not be run"):
            res = SW.sweep(ORBIT_POINTS, orbit=True, on_error="record", **where, **kw)
        assert [r["status"] for r in res.rows] == ["error", "error"], where
        for r in res.rows:
            assert r["error"].startswith("ControllerError: controller Forgets.command(")
            assert "TypeError" in r["error"] and r["orbit_status"] is None
        assert res.settings["n_errors"] == 2
    with pytest.raises(StudyError, match="Forgets.command"):
        SW.sweep(ORBIT_POINTS, workers=1, orbit=True, **kw)


def test_orbit_sensitivities_of_a_users_controller_are_the_same_on_workers_and_on_dask(
    user, dask_client
):
    """orbit_sensitivities at the orbit of a user's controller, its parameters shared out:
    the compiled one's on a Dask cluster and the Python one's on two local workers give
    the numbers of one process; the law is Table I's, so the compiled one's derivatives
    are the built-in law's (another section, other steps: within the orbits' noise). A
    controller that cannot be sent is refused before any parameter runs."""
    robot, cparams = scoutsim.RobotParameters(), scoutsim.ControllerParameters()
    names = ["robot.belt_stiffness", "friction_coefficient"]
    compiled = controlled_fixed_point(
        controller=user.make_compiled(robot, cparams), settle_duration=8.0
    )
    one, _ = orbit_sensitivities(compiled, names, workers=1)
    dask, _ = orbit_sensitivities(compiled, names, scheduler=dask_client)
    assert [one[n].status for n in names] == ["ok", "ok"]
    assert _same(
        {n: s.to_dict() for n, s in dask.items()}, {n: s.to_dict() for n, s in one.items()}
    )
    table_i = controlled_fixed_point(settle_duration=8.0)
    builtin, _ = orbit_sensitivities(table_i, names[:1])
    speed = "mean_speed_m_s"
    d, d_builtin = one[names[0]].derivative[speed], builtin[names[0]].derivative[speed]
    # the orbits' own noise over the step, 1e-9 / h, bounds the metrics' derivatives
    # (docs/explanation/orbit-sensitivities.md); measured 5e-10 (5e-6 of the derivative)
    h = 1e-4 * robot.belt_stiffness
    assert abs(d - d_builtin) < 1e-9 / h
    python = controlled_fixed_point(
        controller=user.make_python(robot, cparams), settle_duration=8.0
    )
    kw = dict(spectral_radius=False)
    here, _ = orbit_sensitivities(python, names, workers=1, **kw)
    two, _ = orbit_sensitivities(python, names, workers=2, **kw)
    assert [here[n].status for n in names] == ["ok", "ok"]
    assert _same(
        {n: s.to_dict() for n, s in two.items()}, {n: s.to_dict() for n, s in here.items()}
    )
    # a controller that cannot be sent is refused before any parameter runs
    closure = dataclasses.replace(
        table_i, setting={**table_i.setting, "controller": _closure_controller(user)}
    )
    with pytest.raises(NotSendableError, match="defined inside a function"):
        orbit_sensitivities(closure, names, workers=2)
