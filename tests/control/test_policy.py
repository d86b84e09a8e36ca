"""PolicyController (scoutsim.control.policy): a learned feed-forward policy run as a
compiled controller. Checked here: the compiled command computes the NumPy reference
evaluation of the policy (observation box, normalisation, network, action box and map)
for tanh and relu networks, with and without normalisation; the action is held over the
policy period (torques), while the Table I law runs at every sample with the held
set-points (set-points); a set-point policy whose action is Table I's set-points makes the
Table I controller's run bit for bit (the law is bounding_step's, not a copy); the policy
file round-trips bit for bit and a bad file is refused naming the field; a policy travels
to worker processes and a Dask cluster (the basin map is the same table as in one
process)."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import scoutsim
from scoutsim.analysis import basin as B
from scoutsim.control import sensors as S
from scoutsim.control.bounding import SCHEDULABLE, bounding_step, controller_array
from scoutsim.control.policy import (
    PolicyAction,
    PolicyController,
    PolicyError,
    PolicyObservation,
)
from scoutsim.parameters import ControllerParameters, RobotParameters

TABLE_I = ControllerParameters()
ROBOT = RobotParameters()
#: the Table I set-points in the order of a set-point action
TABLE_I_SETPOINTS = [getattr(TABLE_I, name) for name in SCHEDULABLE]


def _box(scale=20.0):
    high = np.full(S.N_SENSORS, scale, dtype=np.float32)
    return -high, high


def _layers(rng, widths, out_scale=1.0):
    layers = []
    for i, (n_in, n_out) in enumerate(zip(widths[:-1], widths[1:])):
        w = rng.normal(size=(n_out, n_in)) / np.sqrt(n_in)
        if i == len(widths) - 2:
            w = w * out_scale
        layers.append((w, 0.1 * rng.normal(size=n_out)))
    return layers


def _policy(
    seed=0,
    *,
    activation="tanh",
    normalised=True,
    action_type="torque",
    hidden=(24, 16),
    out_scale=1.0,
    **kw,
):
    """A random policy of the size of a small trained one."""
    rng = np.random.default_rng(seed)
    n_out = 2 if action_type == "torque" else 4
    low, high = _box()
    stats = {}
    if normalised:
        stats = dict(
            mean=rng.normal(size=S.N_SENSORS),
            var=rng.uniform(0.05, 4.0, size=S.N_SENSORS),
            clip=3.0,  # (some normalised readings are clipped)
        )
    if action_type == "torque":
        center, half = np.zeros(2), np.full(2, ROBOT.max_leg_torque)
    else:
        center, half = np.array(TABLE_I_SETPOINTS), np.full(4, 0.3)
    return PolicyController(
        _layers(rng, [S.N_SENSORS, *hidden, n_out], out_scale),
        PolicyObservation(low=low, high=high, **stats),
        PolicyAction(type=action_type, center=center, half_width=half),
        activation=activation,
        **kw,
    )


def _readings(rng, n):
    """Sensor readings of every sign and size, some beyond the observation box."""
    return rng.normal(size=(n, S.N_SENSORS)) * rng.choice([0.1, 1.0, 30.0], size=(n, S.N_SENSORS))


@pytest.mark.parametrize("activation", ["tanh", "relu"])
@pytest.mark.parametrize("normalised", [True, False])
def test_the_compiled_command_computes_the_numpy_evaluation_of_the_policy(activation, normalised):
    """At every policy tick the compiled command's torques are the physical action of the
    NumPy reference (float32 observation clipped to its box, normalised, network, action
    clipped to [-1, 1], mapped) for readings inside and outside the box; some actions hit
    the box (a large output layer)."""
    rng = np.random.default_rng(1)
    p = _policy(2, activation=activation, normalised=normalised, out_scale=3.0)
    ys = _readings(rng, 200)
    got = np.array([_tick(p, i, y) for i, y in enumerate(ys)])
    want = p.physical_action(ys)
    assert np.abs(p.predict(ys)).max() == 1.0  # (the action box is reached)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * ROBOT.max_leg_torque)


def _tick(p: PolicyController, i: int, y) -> tuple[float, float]:
    """The command at the tick of policy step ``i`` for readings ``y`` (the samples in
    between see the same readings)."""
    n = p.samples_per_step
    out = None
    for k in range(i * n, (i + 1) * n):
        tau = p.command(k * p.control_period, S.Sensors.from_vector(y))
        if k == i * n:
            out = tau
    assert out is not None
    return out


def test_the_observation_is_the_float32_reading_clipped_to_its_box():
    """The policy sees a reading as the environment hands it over: rounded to float32,
    then clipped (a reading just beyond a box end is the end)."""
    p = _policy(3, normalised=False)
    y = np.full(S.N_SENSORS, 0.1)
    y[0] = 1e9
    y[1] = -1e9
    obs = p.observation.observe(y)
    assert obs.dtype == np.float32
    assert obs[0] == p.observation.high[0] and obs[1] == p.observation.low[1]
    assert obs[2] == np.float32(0.1) and float(obs[2]) != 0.1


def test_a_torque_action_is_held_over_the_policy_period():
    """Readings that change at every sample: the torques change only at samples 0, n, 2n
    ... (n = policy period / control period), to the action of that sample's readings."""
    rng = np.random.default_rng(4)
    p = _policy(5, policy_period=0.005)
    n = p.samples_per_step
    assert n == 5
    ys = _readings(rng, 4 * n)
    taus = np.array([p.command(k * 1e-3, S.Sensors.from_vector(y)) for k, y in enumerate(ys)])
    for k in range(len(ys)):
        tick = k - k % n
        assert np.array_equal(taus[k], taus[tick])
        np.testing.assert_allclose(taus[k], p.physical_action(ys[tick]), rtol=1e-12, atol=1e-12)
    assert len({tuple(t) for t in taus}) == 4


def test_setpoints_change_at_ticks_while_the_table_i_law_runs_every_sample():
    """A set-point policy: the torque of every sample is Table I's law
    (bounding_step: state machine, flight servo, retraction, brake) with the set-points of
    the last tick; a touchdown between two ticks switches the leg to stance-retraction at
    that sample."""
    rng = np.random.default_rng(6)
    p = _policy(7, action_type="setpoints", normalised=False)
    n = p.samples_per_step
    l0 = ROBOT.leg_rest_length
    ys = []
    for k in range(3 * n):
        y = rng.normal(size=S.N_SENSORS) * 0.2
        # the back leg in flight until sample 13, then compressed (a touchdown between ticks)
        y[S.LEG_LENGTH] = l0 - (0.0 if k < 13 else 0.02)
        y[S.LEG_LENGTH + 1] = l0
        ys.append(y)
    C = controller_array(TABLE_I, ROBOT)
    ls = np.zeros(2, dtype=np.int64)
    tr = np.zeros(2, dtype=np.int64)
    states = []
    for k, y in enumerate(ys):
        if k % n == 0:
            for name, v in zip(SCHEDULABLE, p.physical_action(y)):
                C[SCHEDULABLE[name]] = v
        cmd = np.zeros(2)
        bounding_step(y, C, ls, cmd, tr)
        tau = p.command(k * 1e-3, S.Sensors.from_vector(y))
        np.testing.assert_allclose(tau, cmd, rtol=1e-12, atol=1e-9)
        assert np.array_equal(p.leg_states, ls)
        states.append(int(ls[0]))
    assert states[12] == 0 and states[13] == 1  # (the touchdown at sample 13, not a tick)


@pytest.mark.parametrize("model", ["II", "ideal"])
def test_a_setpoint_policy_choosing_table_i_runs_the_table_i_controller_bit_for_bit(model):
    """The network's output is 0 (an output layer of zeros), the action's centre Table I's
    set-points: the run is the built-in Table I controller's, state for state, from the
    same start (legs at the touchdown angles: the policy's controller parameters)."""
    p = _policy(8, action_type="setpoints")
    zero = [(w, b) for w, b in p.layers[:-1]] + [(np.zeros((4, 16)), np.zeros(4))]
    p = PolicyController(
        zero,
        p.observation,
        PolicyAction(type="setpoints", center=TABLE_I_SETPOINTS, half_width=[0.3] * 4),
    )
    ref = scoutsim.simulate(duration=2.0, model=model)
    got = scoutsim.simulate(controller=p, duration=2.0, model=model)
    assert got.outcome == ref.outcome == "completed"
    assert np.array_equal(got.t, ref.t) and np.array_equal(got.state, ref.state)
    assert np.array_equal(got.modes, ref.modes)


def test_the_file_round_trips_bit_for_bit(tmp_path):
    """save then load: every array, the settings, the Table I parameters and the metadata
    are the same, and so is the packed parameter array."""
    cparams = TABLE_I.replace(flight_kp_back=230.0)
    for p in (
        _policy(9, metadata={"model": "II", "seed": 3}, controller_parameters=cparams),
        _policy(10, activation="relu", normalised=False, action_type="setpoints"),
    ):
        path = tmp_path / "policy.npz"
        p.save(path)
        q = PolicyController.load(path)
        for part, name in [
            ("observation", n) for n in ("low", "high", "mean", "var", "epsilon", "clip")
        ] + [("action", n) for n in ("center", "half_width", "low", "high", "names", "type")]:
            a, b = getattr(getattr(p, part), name), getattr(getattr(q, part), name)
            if isinstance(a, np.ndarray):
                assert a.dtype == b.dtype and np.array_equal(a, b)
            else:
                assert a == b
        assert all(
            np.array_equal(w, v) and np.array_equal(b, c)
            for (w, b), (v, c) in zip(p.layers, q.layers, strict=True)
        )
        assert np.array_equal(p.params, q.params)
        assert (q.activation, q.policy_period) == (p.activation, p.policy_period)
        assert q.controller_parameters == p.controller_parameters
        assert q.metadata == p.metadata


def _fields(p: PolicyController, tmp_path) -> dict:
    path = tmp_path / "good.npz"
    p.save(path)
    with np.load(path) as data:
        return {k: data[k] for k in data.files}


def _bad(**changes):
    def change(fields):
        for k, v in changes.items():
            if v is None:
                fields.pop(k)
            else:
                fields[k] = v
        return fields

    return change


BAD_FILES = {
    "missing weights": (_bad(weights_1=None), "weights_1"),
    "missing field": (_bad(action_center=None), "action_center"),
    "weights of the wrong shape": (_bad(weights_1=np.zeros((16, 23))), "weights_1"),
    "biases of the wrong shape": (_bad(biases_0=np.zeros(3)), "biases_0"),
    "an observation box of the wrong length": (
        _bad(observation_low=np.zeros(3, np.float32)),
        "observation_low",
    ),
    "a variance without a mean": (_bad(observation_mean=None), "observation_mean"),
    "a negative variance": (_bad(observation_var=-np.ones(S.N_SENSORS)), "observation_var"),
    "weights that are not finite": (
        _bad(weights_0=np.full((24, S.N_SENSORS), np.inf)),
        "weights_0",
    ),
    "an unknown activation": (_bad(activation=np.array("sigmoid")), "activation"),
    "an unknown action type": (_bad(action_type=np.array("velocity")), "action_type"),
    "a policy period off the control period": (
        _bad(policy_period=np.array(0.0105)),
        "policy_period",
    ),
    "another format": (_bad(format=np.array("something/2")), "format"),
    "Table I parameters out of range": (
        _bad(controller_parameters=np.array('{"flight_kp_back": -5.0}')),
        "controller_parameters",
    ),
    "a stray layer": (_bad(weights_7=np.zeros((2, 2))), "weights_7"),
}


@pytest.mark.parametrize("case", list(BAD_FILES))
def test_a_bad_file_is_refused_naming_the_field(case, tmp_path):
    change, field = BAD_FILES[case]
    fields = change(_fields(_policy(11), tmp_path))
    path = tmp_path / "bad.npz"
    np.savez(path, **fields)
    with pytest.raises(PolicyError) as err:
        PolicyController.load(path)
    assert err.value.field == field
    assert field in str(err.value) and str(path) in str(err.value)


def test_a_file_that_is_not_a_policy_file_is_refused(tmp_path):
    text = tmp_path / "notes.npz"
    text.write_text("not a zip archive")
    with pytest.raises(PolicyError, match="not a policy file"):
        PolicyController.load(text)
    with pytest.raises(PolicyError, match="no such file"):
        PolicyController.load(tmp_path / "missing.npz")
    np.savez(tmp_path / "arrays.npz", x=np.zeros(3))
    with pytest.raises(PolicyError, match="'format' is missing"):
        PolicyController.load(tmp_path / "arrays.npz")


def test_a_copy_sent_to_a_process_runs_the_same_run():
    """pickle (what a worker process receives): the copy has the same arrays and runs
    the same run, bit for bit (its command function compiled once per process)."""
    p = _policy(12, action_type="setpoints", out_scale=0.01)
    q = pickle.loads(pickle.dumps(p))
    assert q.address == p.address and np.array_equal(q.params, p.params)
    a = scoutsim.simulate(controller=p, duration=0.5)
    b = scoutsim.simulate(controller=q, duration=0.5)
    assert np.array_equal(a.state, b.state)


#: two starts of a short basin map
GRID = dict(models=("II",), speeds=(1.0, 1.3), pitch_rates=(2.0,), heights=(0.34,), duration=3.0)


def test_a_basin_map_with_a_policy_is_the_same_on_workers_and_on_dask(dask_client):
    """The policy travels to two worker processes and to a Dask cluster: the same rows as
    in one process; the set-point policy moves the set-points (its table is not Table
    I's)."""
    p = _policy(13, action_type="setpoints", out_scale=0.05)
    one = B.basin_of_attraction(controller=p, workers=1, **GRID)
    two = B.basin_of_attraction(controller=p, workers=2, **GRID)
    dask = B.basin_of_attraction(controller=p, scheduler=dask_client, **GRID)
    assert [r["status"] for r in one.rows] == ["ok", "ok"]
    assert two.rows == one.rows and dask.rows == one.rows
    builtin = B.basin_of_attraction(controller=None, workers=1, **GRID)
    assert [r["mean_speed_m_s"] for r in one.rows] != [r["mean_speed_m_s"] for r in builtin.rows]
