"""A learned feed-forward policy run as a controller: :class:`PolicyController`.

A policy trained on the learning environment ``scoutsim/Bound-v0``
(:class:`~scoutsim.envs.bound.BoundEnv`), e.g. by Stable-Baselines3's PPO with its
default ``MlpPolicy`` and ``VecNormalize``, is a multilayer perceptron from the sensor
readings to an action. This controller runs it inside the simulator's compiled loop
(a :class:`~scoutsim.control.compiled.CompiledController`), so every study that takes a
controller takes a learned policy: :func:`scoutsim.simulate`, ``scoutsim run``, ``basin``,
``sweep``, ``assumptions``, on worker processes and Dask workers. The policy is what the
environment ran, step for step:

* **policy period**: a policy step is ``samples_per_step`` control samples (the
  environment's ``policy_period`` / ``control_period``, 10 ms / 1 ms by default). At
  sample k of the run (k = 0 the run's first sample) with k a multiple of
  ``samples_per_step``, the policy computes an action from the readings of that sample,
  and holds it for samples k .. k + samples_per_step - 1;
* **observation**: the readings (slots :mod:`scoutsim.control.sensors`, ``HIP_ANGLE`` ...
  ``BATTERY``; SI) cast to float32 and clipped to the observation box ``observation_low``
  .. ``observation_high`` (the environment's observation space), as the environment
  hands them to the agent;
* **normalisation** (optional: a policy trained with Stable-Baselines3's ``VecNormalize``):
  ``clip((obs - mean) / sqrt(var + epsilon), -clip, clip)`` with the running statistics
  ``observation_mean``, ``observation_var``, ``observation_epsilon`` and
  ``observation_clip`` frozen at export;
* **network**: Linear layers, an activation (tanh or relu) after each but the last,
  ``h = W x + b`` with ``W`` (out, in) as PyTorch's ``nn.Linear`` keeps it: the
  ``MlpPolicy``'s ``mlp_extractor.policy_net`` and then its ``action_net``; the
  deterministic action is the network's output (the mean of the Gaussian);
* **action**: clipped to the action box ``action_low`` .. ``action_high`` (-1 .. 1 for the
  environment's normalised actions: what ``model.predict`` does for a Box action space),
  then made physical: ``physical = action_center + action_half_width * action``;
* "torque" actions are the hip torques (back, front) [N m per physical leg, at the leg],
  written to the motors and held; "setpoints" actions are set-points of the Table I
  controller (:data:`~scoutsim.control.bounding.SCHEDULABLE`, named by ``action_names``:
  touchdown angles and sweep limits [rad]), which runs at every sample
  (:func:`~scoutsim.control.bounding.bounding_step`, its stance / flight state machine
  included) with the gains and thresholds of ``controller_parameters`` and the set-points
  the policy last chose.

The arithmetic is float64 throughout (the policy was trained in float32; float64 agrees
with it to about 1e-6 in the action).

Compiled: the parameter array (:func:`policy_array`, slots ``P_*``) packs the settings,
the Table I array of the run's robot (:func:`~scoutsim.control.bounding.controller_array`),
the observation box and statistics, the action map and the layers; the state (slots
``S_*``) holds the sample count, the held action, the Table I array the set-points are
written into, and the network's scratch. The command function, :func:`policy_command`,
is defined at the top level of this module, so the controller pickles (to worker processes
and Dask workers) and compiles once per process.

A policy is kept in a file, ``.npz`` (:meth:`PolicyController.save`,
:meth:`PolicyController.load`; the fields: :data:`FILE_FIELDS`); a Stable-Baselines3
model is exported to one by :func:`scoutsim.envs.policy_export.export_policy`.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from collections.abc import Sequence

import numpy as np

from .._numba.jit import kernel
from ..parameters import ControllerParameters, ParameterError, RobotParameters
from .bounding import NC, SCHEDULABLE, bounding_step, controller_array
from .compiled import CompiledController
from .sensors import N_SENSORS

__all__ = [
    "PolicyController",
    "PolicyError",
    "policy_array",
    "policy_command",
    "ACTION_TYPES",
    "ACTIVATIONS",
    "TORQUE_NAMES",
    "FILE_FORMAT",
    "FILE_FIELDS",
]

#: what an action is: the hip torques, or set-points of the Table I controller
ACTION_TYPES = ("torque", "setpoints")
#: the activations between the layers (the code of each is its index)
ACTIVATIONS = ("tanh", "relu")
#: the names of a torque action's entries: the hip torques [N m], back then front
TORQUE_NAMES = ("hip_torque_back", "hip_torque_front")
#: the most entries an action may have (the four set-points)
MAX_ACTIONS = len(SCHEDULABLE)
#: what the policy file says it is (its ``format`` field)
FILE_FORMAT = "scoutsim.policy/1"

# -- the parameter array -----------------------------------------------------------------
# settings
P_ACTION_TYPE = 0  # index in ACTION_TYPES
P_SAMPLES_PER_STEP = 1  # control samples per policy step
P_ACTIVATION = 2  # index in ACTIVATIONS
P_NORMALISED = 3  # 1.0: the observation is normalised (VecNormalize), 0.0: not
P_OBS_CLIP = 4  # the normalised observation's clip (VecNormalize's clip_obs)
P_N_ACTIONS = 5  # entries of the action
P_N_LAYERS = 6  # Linear layers, the output layer included
P_MAX_WIDTH = 7  # the widest layer's width (scratch)
P_TABLE_I = 8  # the Table I controller array of the run's robot (NC slots, C_*)
P_OBS_LOW = P_TABLE_I + NC  # observation box (N_SENSORS slots, float32 values)
P_OBS_HIGH = P_OBS_LOW + N_SENSORS
P_OBS_MEAN = P_OBS_HIGH + N_SENSORS  # running mean of the observation (N_SENSORS)
P_OBS_STD = P_OBS_MEAN + N_SENSORS  # sqrt(var + epsilon) (N_SENSORS)
P_ACTION_LOW = P_OBS_STD + N_SENSORS  # the action box (MAX_ACTIONS slots)
P_ACTION_HIGH = P_ACTION_LOW + MAX_ACTIONS
P_ACTION_CENTER = P_ACTION_HIGH + MAX_ACTIONS  # physical = center + half_width * action
P_ACTION_HALF_WIDTH = P_ACTION_CENTER + MAX_ACTIONS
P_ACTION_SLOT = P_ACTION_HALF_WIDTH + MAX_ACTIONS  # where each entry goes: leg, or C_* slot
P_WIDTHS = P_ACTION_SLOT + MAX_ACTIONS  # layer widths, input first (N_LAYERS + 1 slots)
# then, layer by layer, the weights (out x in, row by row) and the biases (out)

# -- the state ---------------------------------------------------------------------------
S_SAMPLE = 0  # control samples run so far
S_ACTION = 1  # the held physical action (MAX_ACTIONS slots; N m or rad)
S_TABLE_I = S_ACTION + MAX_ACTIONS  # the Table I array with the held set-points (NC)
S_SCRATCH = S_TABLE_I + NC  # the network's two layer buffers (2 x P_MAX_WIDTH)

#: the fields of a policy file (``.npz``; ``{i}`` a layer's index, 0 the first): name ->
#: what it holds
FILE_FIELDS = {
    "format": f'"{FILE_FORMAT}"',
    "weights_{i}": "layer i's weights, (out, in), float64",
    "biases_{i}": "layer i's biases, (out,), float64",
    "activation": "between the layers: " + " or ".join(f'"{a}"' for a in ACTIVATIONS),
    "observation_low": f"the observation box's low end, ({N_SENSORS},) float32",
    "observation_high": f"the observation box's high end, ({N_SENSORS},) float32",
    "observation_mean": f"(optional) the normalisation's running mean, ({N_SENSORS},) float64",
    "observation_var": f"(optional) its running variance, ({N_SENSORS},) float64",
    "observation_epsilon": "(with the mean) added to the variance, float64",
    "observation_clip": "(with the mean) the normalised observation's clip, float64",
    "action_type": " or ".join(f'"{a}"' for a in ACTION_TYPES),
    "action_names": "the action's entries (hip torques, or Table I set-point fields)",
    "action_low": "the box the network's output is clipped to, float64",
    "action_high": "its high end, float64",
    "action_center": "physical action = center + half_width * action [N m or rad]",
    "action_half_width": "[N m or rad], float64",
    "policy_period": "time between two actions [s]",
    "controller_parameters": "the Table I parameters, JSON (SI)",
    "metadata": "the model it was trained on and its provenance, JSON",
}


class PolicyError(ValueError):
    """A policy (its arrays, or a policy file) that is not allowed: the message names the
    field and what it must be."""

    def __init__(self, message: str, field: str | None = None):
        super().__init__(message)
        self.field = field


# -- the compiled law --------------------------------------------------------------------


@kernel
def _layers_start(params):
    """The first slot of the layers' weights in ``params``."""
    return P_WIDTHS + int(params[P_N_LAYERS]) + 1


@kernel
def network_action(y, params, scratch, action):
    """The policy's action (in its own units, clipped to its box) for the readings ``y``
    (``layout.SN_*``, SI) into ``action``; ``scratch``: 2 x ``P_MAX_WIDTH`` floats.
    The observation (float32, clipped to its box), its normalisation and the network as
    the module docstring says."""
    width = int(params[P_MAX_WIDTH])
    a = scratch[:width]
    b = scratch[width : 2 * width]
    normalised = params[P_NORMALISED] != 0.0
    clip = params[P_OBS_CLIP]
    for i in range(N_SENSORS):
        o = np.float64(np.float32(y[i]))
        lo = params[P_OBS_LOW + i]
        hi = params[P_OBS_HIGH + i]
        if o < lo:
            o = lo
        elif o > hi:
            o = hi
        if normalised:
            o = (o - params[P_OBS_MEAN + i]) / params[P_OBS_STD + i]
            if o < -clip:
                o = -clip
            elif o > clip:
                o = clip
        a[i] = o
    n_layers = int(params[P_N_LAYERS])
    tanh = int(params[P_ACTIVATION]) == 0
    at = _layers_start(params)
    for layer in range(n_layers):
        n_in = int(params[P_WIDTHS + layer])
        n_out = int(params[P_WIDTHS + layer + 1])
        w = at
        bias = at + n_out * n_in
        last = layer == n_layers - 1
        for j in range(n_out):
            h = params[bias + j]
            row = w + j * n_in
            for i in range(n_in):
                h += params[row + i] * a[i]
            if not last:
                h = math.tanh(h) if tanh else (h if h > 0.0 else 0.0)
            b[j] = h
        at = bias + n_out
        a, b = b, a
    for i in range(int(params[P_N_ACTIONS])):
        v = a[i]
        lo = params[P_ACTION_LOW + i]
        hi = params[P_ACTION_HIGH + i]
        if v < lo:
            v = lo
        elif v > hi:
            v = hi
        action[i] = v


def policy_command(t, y, params, state, torque, leg_states):
    """One control sample of the policy (see the module docstring): at a policy tick the
    action from the readings ``y`` is computed and held (``state[S_ACTION:]``; set-points
    also into the state's Table I array); then the torques of the held action, or of the
    Table I law with the held set-points, per physical leg [N m]. Returns 0."""
    k = int(state[S_SAMPLE])
    setpoints = int(params[P_ACTION_TYPE]) == 1
    n_actions = int(params[P_N_ACTIONS])
    if k == 0 and setpoints:  # the run's first sample: Table I as packed for its robot
        for i in range(NC):
            state[S_TABLE_I + i] = params[P_TABLE_I + i]
    if k % int(params[P_SAMPLES_PER_STEP]) == 0:
        width = int(params[P_MAX_WIDTH])
        action = state[S_ACTION : S_ACTION + n_actions]
        network_action(y, params, state[S_SCRATCH : S_SCRATCH + 2 * width], action)
        for i in range(n_actions):
            v = params[P_ACTION_CENTER + i] + params[P_ACTION_HALF_WIDTH + i] * action[i]
            action[i] = v
            if setpoints:
                state[S_TABLE_I + int(params[P_ACTION_SLOT + i])] = v
    state[S_SAMPLE] = k + 1
    if setpoints:
        transitions = np.zeros(2, dtype=np.int64)
        bounding_step(y, state[S_TABLE_I : S_TABLE_I + NC], leg_states, torque, transitions)
    else:
        for i in range(n_actions):
            torque[int(params[P_ACTION_SLOT + i])] = state[S_ACTION + i]
    return 0


# -- the controller ----------------------------------------------------------------------


def _array(value, field: str, *, shape=None, dtype=np.float64) -> np.ndarray:
    """``value`` as an array of ``dtype`` (and ``shape``), with no NaN; PolicyError naming
    ``field`` otherwise."""
    try:
        a = np.array(value, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise PolicyError(
            f"{field} is not allowed: not an array of numbers ({exc})", field
        ) from None
    if shape is not None and a.shape != tuple(shape):
        raise PolicyError(
            f"{field} has shape {a.shape}: must be {tuple(shape)}",
            field,
        )
    if np.isnan(a).any():
        raise PolicyError(f"{field} is not allowed: it holds NaN", field)
    return a


def _finite(a: np.ndarray, field: str) -> np.ndarray:
    if not np.isfinite(a).all():
        raise PolicyError(f"{field} is not allowed: every entry must be finite", field)
    return a


class PolicyController(CompiledController):
    """A learned feed-forward policy run as a controller, compiled into the simulator's
    loop (see the module docstring for what it computes).

    Parameters
    ----------
    layers : sequence of (weights, biases)
        The Linear layers in order, the output layer last: ``weights`` (out, in) and
        ``biases`` (out,) as PyTorch's ``nn.Linear`` keeps them; the first takes the
        ``N_SENSORS`` readings, the last gives the action.
    activation : {"tanh", "relu"}
        After every layer but the last (Stable-Baselines3's ``MlpPolicy``: tanh).
    observation_low, observation_high : (N_SENSORS,) arrays
        The observation box the readings are clipped to (the environment's observation
        space; float32 values, SI units of each slot).
    observation_mean, observation_var : (N_SENSORS,) arrays, optional
        The normalisation's running mean and variance (``VecNormalize.obs_rms``); None:
        the observation is not normalised.
    observation_epsilon : float
        Added to the variance (``VecNormalize.epsilon``, default 1e-8).
    observation_clip : float
        The normalised observation's clip (``VecNormalize.clip_obs``, default 10).
    action_type : {"torque", "setpoints"}
        What the action is (module docstring).
    action_center, action_half_width : arrays of the action's length
        physical = center + half_width * action [N m per leg for torques, rad for
        set-points]; as the environment mapped it (``action_center`` and
        ``action_half_width`` of :class:`~scoutsim.envs.bound.BoundEnv`).
    action_low, action_high : arrays of the action's length, optional
        The box the network's output is clipped to (default -1 and 1: normalised actions).
    action_names : sequence of str, optional
        The action's entries: for torques :data:`TORQUE_NAMES` (the default); for
        set-points fields of :data:`~scoutsim.control.bounding.SCHEDULABLE` (default:
        all four in its order, the environment's ``SETPOINTS``).
    policy_period : float
        Time between two actions [s] (default 0.01), a whole multiple of the control
        period.
    controller_parameters : ControllerParameters, optional
        The Table I parameters of the environment the policy was trained in (default:
        Table I): the gains and thresholds the set-points run with, the control period,
        the legs' angles at a start in flight and which side the hip encoders read
        (``sense_motor_angle``), as for the Table I controller.
    metadata : dict, optional
        JSON-safe facts about the policy: the model and environment it was trained on,
        the training's provenance (kept in its file).
    name : str, optional
        How errors and provenance name it (default "PolicyController").

    Attributes
    ----------
    samples_per_step : int
        Control samples per policy step.
    params : the parameter array packed with Scout II's constants (:func:`policy_array`);
        a run packs its robot's (:meth:`params_for`).

    Picklable (its arrays travel; the compiled function is compiled once per process).
    """

    def __init__(
        self,
        layers: Sequence,
        *,
        observation_low,
        observation_high,
        action_center,
        action_half_width,
        activation: str = "tanh",
        observation_mean=None,
        observation_var=None,
        observation_epsilon: float = 1e-8,
        observation_clip: float = 10.0,
        action_type: str = "torque",
        action_low=None,
        action_high=None,
        action_names: Sequence[str] | None = None,
        policy_period: float = 0.01,
        controller_parameters: ControllerParameters | None = None,
        metadata: dict | None = None,
        name: str | None = None,
    ):
        if action_type not in ACTION_TYPES:
            raise PolicyError(
                f"action_type = {action_type!r} is not allowed: must be one of "
                f"{list(ACTION_TYPES)}",
                "action_type",
            )
        if activation not in ACTIVATIONS:
            raise PolicyError(
                f"activation = {activation!r} is not allowed: must be one of {list(ACTIVATIONS)}",
                "activation",
            )
        self.action_type = action_type
        self.activation = activation
        self.layers = _check_layers(layers)
        n_actions = self.layers[-1][1].shape[0]
        self.action_names = _check_names(action_names, action_type, n_actions)
        self.observation_low = _array(
            observation_low, "observation_low", shape=(N_SENSORS,), dtype=np.float32
        )
        self.observation_high = _array(
            observation_high, "observation_high", shape=(N_SENSORS,), dtype=np.float32
        )
        if (self.observation_low > self.observation_high).any():
            raise PolicyError(
                "observation_low is not allowed: above observation_high in slots "
                f"{np.flatnonzero(self.observation_low > self.observation_high).tolist()}",
                "observation_low",
            )
        if (observation_mean is None) != (observation_var is None):
            raise PolicyError(
                "observation_mean and observation_var go together: give both (a "
                "normalised observation) or neither",
                "observation_mean" if observation_mean is None else "observation_var",
            )
        self.observation_mean = self.observation_var = None
        if observation_mean is not None:
            self.observation_mean = _finite(
                _array(observation_mean, "observation_mean", shape=(N_SENSORS,)),
                "observation_mean",
            )
            var = _finite(
                _array(observation_var, "observation_var", shape=(N_SENSORS,)), "observation_var"
            )
            if (var < 0).any():
                raise PolicyError("observation_var is not allowed: must be >= 0", "observation_var")
            self.observation_var = var
        self.observation_epsilon = _positive(observation_epsilon, "observation_epsilon")
        self.observation_clip = _positive(observation_clip, "observation_clip")
        if (
            self.observation_var is not None
            and not (np.sqrt(self.observation_var + self.observation_epsilon) > 0).all()
        ):
            raise PolicyError(
                "observation_var + observation_epsilon must be > 0", "observation_epsilon"
            )
        shape = (n_actions,)
        self.action_center = _finite(
            _array(action_center, "action_center", shape=shape), "action_center"
        )
        self.action_half_width = _finite(
            _array(action_half_width, "action_half_width", shape=shape), "action_half_width"
        )
        self.action_low = _finite(
            _array(
                -np.ones(shape) if action_low is None else action_low, "action_low", shape=shape
            ),
            "action_low",
        )
        self.action_high = _finite(
            _array(
                np.ones(shape) if action_high is None else action_high, "action_high", shape=shape
            ),
            "action_high",
        )
        if (self.action_low > self.action_high).any():
            raise PolicyError("action_low is not allowed: above action_high", "action_low")
        cparams = (
            controller_parameters if controller_parameters is not None else ControllerParameters()
        )
        if not isinstance(cparams, ControllerParameters):
            raise PolicyError(
                f"controller_parameters must be ControllerParameters, not {type(cparams).__name__}",
                "controller_parameters",
            )
        self.controller_parameters = cparams
        dt = cparams.control_period
        n = round(policy_period / dt) if math.isfinite(policy_period) and policy_period > 0 else 0
        if not (n >= 1 and abs(n * dt - policy_period) <= 1e-9 * policy_period):
            raise PolicyError(
                f"policy_period = {policy_period!r} s is not allowed: must be a whole "
                f"multiple (>= 1) of the control period {dt:g} s",
                "policy_period",
            )
        self.samples_per_step = int(n)
        self.policy_period = float(policy_period)
        self.metadata = dict(metadata or {})
        try:
            json.dumps(self.metadata)
        except (TypeError, ValueError) as exc:
            raise PolicyError(
                f"metadata is not allowed: not JSON-safe ({exc})", "metadata"
            ) from None
        width = max(w.shape[0] for w, _ in self.layers) if self.layers else 0
        width = max(width, N_SENSORS)
        super().__init__(
            policy_command,
            params=policy_array(self),
            state=np.zeros(S_SCRATCH + 2 * width),
            control_period=dt,
            name=name or "PolicyController",
        )

    # -- what the simulator asks -----------------------------------------------------------

    def params_for(self, robot: RobotParameters) -> np.ndarray:
        """The parameter array for a run of ``robot`` (its leg rest length and motor
        constants in the Table I array, as the Table I controller packs them)."""
        return policy_array(self, robot)

    # -- the policy in NumPy ---------------------------------------------------------------

    @property
    def normalised(self) -> bool:
        """True if the observation is normalised (a policy trained with VecNormalize)."""
        return self.observation_mean is not None

    def observation(self, readings) -> np.ndarray:
        """The observation the policy sees for sensor readings ``readings`` ((N_SENSORS,)
        or (n, N_SENSORS), SI): cast to float32 and clipped to the observation box, as
        the environment hands them to the agent (float32)."""
        r = np.asarray(readings)
        return np.clip(r.astype(np.float32), self.observation_low, self.observation_high)

    def predict(self, observation) -> np.ndarray:
        """The policy's deterministic action (in its own units, clipped to its box; float64)
        for an observation or sensor readings ((N_SENSORS,) or a batch (n, N_SENSORS)),
        computed with NumPy: as Stable-Baselines3's
        ``model.predict(vec_normalize.normalize_obs(obs), deterministic=True)``."""
        x = self.observation(observation).astype(np.float64)
        if self.normalised:
            assert self.observation_mean is not None and self.observation_var is not None
            std = np.sqrt(self.observation_var + self.observation_epsilon)
            c = self.observation_clip
            x = np.clip((x - self.observation_mean) / std, -c, c)
        for i, (w, b) in enumerate(self.layers):
            x = x @ w.T + b
            if i < len(self.layers) - 1:
                x = np.tanh(x) if self.activation == "tanh" else np.maximum(x, 0.0)
        return np.clip(x, self.action_low, self.action_high)

    @property
    def held_action(self) -> np.ndarray | None:
        """The physical action [N m per leg, or rad] held by the compiled command after the
        last :meth:`command` call from Python (None before the first); a run's own is in
        the run's controller state."""
        state = getattr(self, "_py_state", None)
        if state is None:
            return None
        return state[S_ACTION : S_ACTION + len(self.action_names)].copy()

    def compiled_action(self, readings) -> np.ndarray:
        """The action (in the policy's own units, as :meth:`predict`) for the sensor
        readings ``readings`` ((N_SENSORS,), SI) computed by the compiled evaluation the
        command runs at a policy tick (:func:`network_action`), not by NumPy."""
        y = np.array(readings, dtype=np.float64).reshape(N_SENSORS)
        out = np.zeros(len(self.action_names))
        network_action(y, self.params, np.zeros(2 * int(self.params[P_MAX_WIDTH])), out)
        return out

    def physical_action(self, observation) -> np.ndarray:
        """The physical action [N m per leg, or rad] of :meth:`predict`'s action."""
        return self.action_center + self.action_half_width * self.predict(observation)

    # -- the file --------------------------------------------------------------------------

    def save(self, path) -> None:
        """Write the policy to ``path`` (``.npz``, fields :data:`FILE_FIELDS`);
        :meth:`load` reads it back, every array bit for bit."""
        cparams = self.controller_parameters
        assert cparams is not None  # (set by the constructor)
        fields: dict[str, np.ndarray] = {
            "format": np.array(FILE_FORMAT),
            "activation": np.array(self.activation),
            "observation_low": self.observation_low,
            "observation_high": self.observation_high,
            "action_type": np.array(self.action_type),
            "action_names": np.array(self.action_names),
            "action_low": self.action_low,
            "action_high": self.action_high,
            "action_center": self.action_center,
            "action_half_width": self.action_half_width,
            "policy_period": np.array(self.policy_period),
            "controller_parameters": np.array(json.dumps(dataclasses.asdict(cparams))),
            "metadata": np.array(json.dumps(self.metadata, sort_keys=True)),
        }
        if self.normalised:
            assert self.observation_mean is not None and self.observation_var is not None
            fields.update(
                observation_mean=self.observation_mean,
                observation_var=self.observation_var,
                observation_epsilon=np.array(self.observation_epsilon),
                observation_clip=np.array(self.observation_clip),
            )
        for i, (w, b) in enumerate(self.layers):
            fields[f"weights_{i}"] = w
            fields[f"biases_{i}"] = b
        from ..io.run_directory import atomic_write

        path = os.fspath(path)
        if not path.endswith(".npz"):
            raise PolicyError(f"a policy file's name ends in .npz, not {path!r}", "path")
        atomic_write(path, lambda tmp: np.savez(tmp, allow_pickle=False, **fields))

    @classmethod
    def load(cls, path) -> PolicyController:
        """The policy of the file ``path`` (as :meth:`save` writes it, or
        :func:`scoutsim.envs.policy_export.export_policy`), named after the file
        (``PolicyController(policy.npz)``: how errors and a run's provenance name it).
        PolicyError naming the file and the field if a field is missing or not allowed
        (shapes, values)."""
        path = os.fspath(path)
        try:
            with np.load(path, allow_pickle=False) as data:
                fields = {k: data[k] for k in data.files}
        except FileNotFoundError:
            raise PolicyError(f"policy file {path!r}: no such file", "path") from None
        except (OSError, ValueError) as exc:
            raise PolicyError(
                f"policy file {path!r}: not a policy file (.npz, numbers only): {exc}", "path"
            ) from None
        try:
            return cls._from_fields(fields, name=f"PolicyController({os.path.basename(path)})")
        except PolicyError as exc:
            raise PolicyError(f"policy file {path!r}: {exc}", exc.field) from None

    @classmethod
    def _from_fields(cls, f: dict, name: str | None = None) -> PolicyController:
        def need(name):
            if name not in f:
                raise PolicyError(f"field {name!r} is missing ({FILE_FIELDS.get(name, '')})", name)
            return f[name]

        def text(name) -> str:
            v = need(name)
            if v.shape != () or v.dtype.kind != "U":
                raise PolicyError(f"field {name!r} must be one string", name)
            return str(v)

        def number(name) -> float:
            v = need(name)
            if v.shape != () or v.dtype.kind not in "fiu":
                raise PolicyError(f"field {name!r} must be one number", name)
            return float(v)

        def json_field(name) -> dict:
            try:
                out = json.loads(text(name))
            except json.JSONDecodeError as exc:
                raise PolicyError(f"field {name!r} is not JSON: {exc}", name) from None
            if not isinstance(out, dict):
                raise PolicyError(f"field {name!r} must be a JSON object", name)
            return out

        fmt = text("format")
        if fmt != FILE_FORMAT:
            raise PolicyError(
                f"field 'format' = {fmt!r}: this scoutsim reads {FILE_FORMAT!r}", "format"
            )
        layers = []
        i = 0
        while f"weights_{i}" in f or f"biases_{i}" in f:
            layers.append((need(f"weights_{i}"), need(f"biases_{i}")))
            i += 1
        if not layers:
            raise PolicyError("field 'weights_0' is missing (the first layer)", "weights_0")
        stray = sorted(
            k for k in f if k.startswith(("weights_", "biases_")) and not _layer_key(k, i)
        )
        if stray:
            raise PolicyError(f"fields {stray} do not follow layers 0 .. {i - 1}", stray[0])
        cdict = json_field("controller_parameters")
        try:
            cparams = ControllerParameters(**cdict)
        except (TypeError, ParameterError) as exc:
            raise PolicyError(
                f"field 'controller_parameters' is not allowed: {exc}", "controller_parameters"
            ) from None
        normalised = "observation_mean" in f or "observation_var" in f
        names = need("action_names")
        if names.ndim != 1 or names.dtype.kind != "U":
            raise PolicyError("field 'action_names' must be a list of strings", "action_names")
        return cls(
            layers,
            activation=text("activation"),
            observation_low=need("observation_low"),
            observation_high=need("observation_high"),
            observation_mean=need("observation_mean") if normalised else None,
            observation_var=need("observation_var") if normalised else None,
            observation_epsilon=number("observation_epsilon") if normalised else 1e-8,
            observation_clip=number("observation_clip") if normalised else 10.0,
            action_type=text("action_type"),
            action_names=[str(n) for n in names],
            action_low=need("action_low"),
            action_high=need("action_high"),
            action_center=need("action_center"),
            action_half_width=need("action_half_width"),
            policy_period=number("policy_period"),
            controller_parameters=cparams,
            metadata=json_field("metadata"),
            name=name,
        )

    def __repr__(self):
        widths = [self.layers[0][0].shape[1]] + [w.shape[0] for w, _ in self.layers]
        return (
            f"PolicyController({self.action_type}, layers {'-'.join(map(str, widths))} "
            f"{self.activation}, {'normalised' if self.normalised else 'raw'} observation, "
            f"policy period {self.policy_period:g} s)"
        )


def _layer_key(key: str, n_layers: int) -> bool:
    """``key`` is ``weights_{i}`` or ``biases_{i}`` of a layer 0 .. n_layers - 1."""
    index = key.partition("_")[2]
    return index.isdigit() and str(int(index)) == index and int(index) < n_layers


def _positive(value, field: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise PolicyError(
            f"{field} = {value!r} is not allowed: must be a number > 0", field
        ) from None
    if not (math.isfinite(v) and v > 0):
        raise PolicyError(f"{field} = {value!r} is not allowed: must be a finite number > 0", field)
    return v


def _check_layers(layers) -> list[tuple[np.ndarray, np.ndarray]]:
    """The layers as float64 (weights (out, in), biases (out,)), checked: finite, each
    layer's input the last one's output, the first's the N_SENSORS readings."""
    out: list[tuple[np.ndarray, np.ndarray]] = []
    try:
        pairs = list(layers)
    except TypeError:
        raise PolicyError("layers must be a sequence of (weights, biases)", "layers") from None
    if not pairs:
        raise PolicyError("layers is empty: give at least the output layer", "layers")
    n_in = N_SENSORS
    for i, pair in enumerate(pairs):
        try:
            w, b = pair
        except (TypeError, ValueError):
            raise PolicyError(
                f"layer {i} must be a pair (weights, biases)", f"weights_{i}"
            ) from None
        w = _finite(_array(w, f"weights_{i}"), f"weights_{i}")
        b = _finite(_array(b, f"biases_{i}"), f"biases_{i}")
        if w.ndim != 2 or w.shape[1] != n_in or w.shape[0] < 1:
            what = "the readings" if i == 0 else f"layer {i - 1}'s outputs"
            raise PolicyError(
                f"weights_{i} has shape {w.shape}: must be (out, {n_in}), {n_in} the "
                f"number of {what}",
                f"weights_{i}",
            )
        if b.shape != (w.shape[0],):
            raise PolicyError(
                f"biases_{i} has shape {b.shape}: must be ({w.shape[0]},), one per row of "
                f"weights_{i}",
                f"biases_{i}",
            )
        out.append((w, b))
        n_in = w.shape[0]
    if n_in > MAX_ACTIONS:
        raise PolicyError(
            f"weights_{len(pairs) - 1} gives {n_in} outputs: an action has at most "
            f"{MAX_ACTIONS} entries",
            f"weights_{len(pairs) - 1}",
        )
    return out


def _check_names(names, action_type: str, n_actions: int) -> tuple[str, ...]:
    """The action's entries (see :class:`PolicyController`), checked against its type and
    length."""
    if names is None:
        names = TORQUE_NAMES if action_type == "torque" else tuple(SCHEDULABLE)
    names = tuple(str(n) for n in names)
    allowed = TORQUE_NAMES if action_type == "torque" else tuple(SCHEDULABLE)
    if len(names) != n_actions or len(set(names)) != len(names) or not set(names) <= set(allowed):
        raise PolicyError(
            f"action_names = {list(names)} is not allowed: the network gives "
            f"{n_actions} outputs; a {action_type} action names "
            + (
                f"{list(TORQUE_NAMES)}"
                if action_type == "torque"
                else f"distinct set-points of {list(SCHEDULABLE)}"
            ),
            "action_names",
        )
    if action_type == "torque" and names != TORQUE_NAMES:
        raise PolicyError(
            f"action_names = {list(names)} is not allowed: a torque action is {list(TORQUE_NAMES)}",
            "action_names",
        )
    return names


def policy_array(policy: PolicyController, robot: RobotParameters | None = None) -> np.ndarray:
    """The parameter array of ``policy``'s compiled command (slots ``P_*``, module
    docstring) for a run of ``robot`` (default Scout II): its Table I array packed with that
    robot's constants."""
    n_actions = len(policy.action_names)
    widths = [N_SENSORS] + [w.shape[0] for w, _ in policy.layers]
    size = P_WIDTHS + len(widths) + sum(w.size + b.size for w, b in policy.layers)
    a = np.zeros(size)
    a[P_ACTION_TYPE] = ACTION_TYPES.index(policy.action_type)
    a[P_SAMPLES_PER_STEP] = policy.samples_per_step
    a[P_ACTIVATION] = ACTIVATIONS.index(policy.activation)
    a[P_NORMALISED] = 1.0 if policy.normalised else 0.0
    a[P_OBS_CLIP] = policy.observation_clip
    a[P_N_ACTIONS] = n_actions
    a[P_N_LAYERS] = len(policy.layers)
    a[P_MAX_WIDTH] = max(widths)
    a[P_TABLE_I : P_TABLE_I + NC] = controller_array(policy.controller_parameters, robot)
    a[P_OBS_LOW : P_OBS_LOW + N_SENSORS] = policy.observation_low
    a[P_OBS_HIGH : P_OBS_HIGH + N_SENSORS] = policy.observation_high
    if policy.normalised:
        assert policy.observation_var is not None
        a[P_OBS_MEAN : P_OBS_MEAN + N_SENSORS] = policy.observation_mean
        a[P_OBS_STD : P_OBS_STD + N_SENSORS] = np.sqrt(
            policy.observation_var + policy.observation_epsilon
        )
    a[P_ACTION_LOW : P_ACTION_LOW + n_actions] = policy.action_low
    a[P_ACTION_HIGH : P_ACTION_HIGH + n_actions] = policy.action_high
    a[P_ACTION_CENTER : P_ACTION_CENTER + n_actions] = policy.action_center
    a[P_ACTION_HALF_WIDTH : P_ACTION_HALF_WIDTH + n_actions] = policy.action_half_width
    slots = (
        [TORQUE_NAMES.index(n) for n in policy.action_names]
        if policy.action_type == "torque"
        else [SCHEDULABLE[n] for n in policy.action_names]
    )
    a[P_ACTION_SLOT : P_ACTION_SLOT + n_actions] = slots
    a[P_WIDTHS : P_WIDTHS + len(widths)] = widths
    at = P_WIDTHS + len(widths)
    for w, b in policy.layers:
        a[at : at + w.size] = w.ravel()
        at += w.size
        a[at : at + b.size] = b
        at += b.size
    return a
