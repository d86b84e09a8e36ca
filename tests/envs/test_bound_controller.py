"""A user's controller named "MODULE:FACTORY" in scoutsim/Bound-v0 (scoutsim/envs/bound.py
with scoutsim/control/factory.py): the factory is called with the environment's robot and
Table I parameters, what it makes is the controller the set-points drive (the same episode
bit for bit as passing those parameters), the string is what travels to the workers of an
async vector environment, and a factory that cannot serve gets a clear error."""

import textwrap

import numpy as np
import pytest

gymnasium = pytest.importorskip(
    "gymnasium", reason="the learning environment needs gymnasium (pip install 'scoutsim[rl]')"
)

import scoutsim  # noqa: E402
import scoutsim.envs  # noqa: E402,F401
from scoutsim.control.factory import FactoryError  # noqa: E402
from scoutsim.envs.bound import BoundEnv  # noqa: E402

ID = "scoutsim/Bound-v0"
#: the set-point action that runs the controller as it is (Table I by default): the
#: normalised action 0, the controller's own set-points
TABLE_I_SETPOINTS = np.zeros(4, dtype=np.float32)

MODULE = textwrap.dedent('''
    from scoutsim.control.bounding import BoundingController
    from scoutsim.control.protocol import Controller

    SEEN = []

    def soft(robot, params):
        """Table I with the flight servos at a third of their gains."""
        SEEN.append((robot, params))
        return params.replace(flight_kp_back=params.flight_kp_back / 3,
                              flight_kp_front=params.flight_kp_front / 3)

    def builtin():
        return BoundingController()

    class Own(Controller):
        def command(self, t, sensors):
            return 0.0, 0.0

    def own(robot):
        return Own()
''')


@pytest.fixture
def gaits(tmp_path, monkeypatch):
    """A module of factories on sys.path (and PYTHONPATH, for worker processes)."""
    name = f"user_gaits_{tmp_path.name.replace('-', '_')}"
    (tmp_path / f"{name}.py").write_text(MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    import importlib

    return importlib.import_module(name)


def _episode(env, n=40):
    obs, _ = env.reset(seed=0)
    out = [obs]
    for _ in range(n):
        obs, reward, terminated, truncated, _ = env.step(TABLE_I_SETPOINTS)
        out += [obs, [reward]]
        if terminated or truncated:
            break
    return np.concatenate(out)


def test_the_factory_makes_the_table_i_parameters_for_the_envs_robot(gaits):
    spec = f"{gaits.__name__}:soft"
    env = BoundEnv(model="ideal", action_type="setpoints", controller=spec, current_limit=11.0)
    robot, params = gaits.SEEN[-1]
    # called with the environment's robot (the keyword applied) and the Table I defaults
    assert robot == env.robot and robot.current_limit == 11.0
    assert params == scoutsim.ControllerParameters()
    assert env.controller == params.replace(
        flight_kp_back=params.flight_kp_back / 3, flight_kp_front=params.flight_kp_front / 3
    )
    assert env.controller_spec == spec
    # the episode is that of the parameters passed as an object, not Table I's
    same = BoundEnv(
        model="ideal", action_type="setpoints", controller=env.controller, current_limit=11.0
    )
    table_i = BoundEnv(model="ideal", action_type="setpoints", current_limit=11.0)
    a = _episode(env)
    assert np.array_equal(a, _episode(same))
    assert not np.array_equal(a, _episode(table_i))


def test_keywords_apply_over_the_factorys_parameters(gaits):
    env = BoundEnv(model="ideal", controller=f"{gaits.__name__}:soft", flight_kp_back=7.0)
    assert env.controller.flight_kp_back == 7.0
    assert env.controller.flight_kp_front == scoutsim.ControllerParameters().flight_kp_front / 3


def test_a_bounding_controller_with_the_builtin_law_gives_its_parameters(gaits):
    env = BoundEnv(model="ideal", controller=f"{gaits.__name__}:builtin")
    assert env.controller == scoutsim.ControllerParameters()


def test_a_factory_the_environment_cannot_run_gets_a_clear_error(gaits):
    with pytest.raises(FactoryError, match="Own.*ControllerParameters"):
        BoundEnv(model="ideal", controller=f"{gaits.__name__}:own")
    with pytest.raises(ValueError, match="MODULE:FACTORY"):
        BoundEnv(model="ideal", controller="not a spec")
    with pytest.raises(FactoryError, match="cannot import"):
        BoundEnv(model="ideal", controller="no_such_module_here:make")


def test_the_string_travels_to_async_workers(gaits):
    spec = f"{gaits.__name__}:soft"
    envs = gymnasium.make_vec(
        ID,
        num_envs=2,
        vectorization_mode="async",
        model="ideal",
        action_type="setpoints",
        controller=spec,
    )
    try:
        obs, _ = envs.reset(seed=0)
        for _ in range(3):
            obs, _, terminated, truncated, _ = envs.step(np.tile(TABLE_I_SETPOINTS, (2, 1)))
        assert not (terminated.any() or truncated.any())
        controllers = envs.get_attr("controller")
        assert all(
            c.flight_kp_back == scoutsim.ControllerParameters().flight_kp_back / 3
            for c in controllers
        )
    finally:
        envs.close()


def test_with_a_robot_file_the_factory_gets_its_controller_section(gaits, tmp_path):
    f = tmp_path / "robot.toml"
    f.write_text(
        "[robot]\ntorso_mass = 21.0\n\n[controller]\n"
        'touchdown_angle_front = { value = 22.0, unit = "deg" }\n'
    )
    env = BoundEnv(model="ideal", robot_file=str(f), controller=f"{gaits.__name__}:soft")
    robot, params = gaits.SEEN[-1]
    assert robot == env.robot and robot.torso_mass == 21.0
    assert params.touchdown_angle_front == pytest.approx(np.radians(22.0))
    assert env.controller.touchdown_angle_front == params.touchdown_angle_front
    assert env.controller.flight_kp_front == params.flight_kp_front / 3
