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

The arithmetic is float64 throughout (the policy was trained in float32; the two agree to
float32's rounding, about 1e-7 of the action).

Compiled: the parameter array (:func:`policy_array`, slots ``P_*``) packs the settings,
the Table I array of the run's robot (:func:`~scoutsim.control.bounding.controller_array`),
the observation box and statistics, the action map and the layers; the state (slots
``S_*``) holds the sample count, the held action, the Table I array the set-points are
written into, and the network's scratch. The command function, :func:`policy_command`,
is defined at the top level of this module, so the controller pickles (to worker processes
and Dask workers) and compiles once per process.

A policy is kept in a file, ``.npz`` (:meth:`PolicyController.save`,
:meth:`PolicyController.load`; the fields:
:data:`~scoutsim.control.policy_file.FILE_FIELDS`); what it sees and what its output
means are :class:`~scoutsim.control.policy_spaces.PolicyObservation` and
:class:`~scoutsim.control.policy_spaces.PolicyAction`; a Stable-Baselines3
model is exported to one by :func:`scoutsim.envs.policy_export.export_policy`.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence

import numpy as np

from .._numba.jit import kernel
from ..parameters import ControllerParameters, RobotParameters
from .bounding import NC, bounding_step, controller_array
from .compiled import CompiledController
from .policy_file import read_policy_file, write_policy_file
from .policy_spaces import (
    ACTION_TYPES,
    MAX_ACTIONS,
    PolicyAction,
    PolicyError,
    PolicyObservation,
    checked_array,
)
from .sensors import N_SENSORS

__all__ = [
    "PolicyController",
    "PolicyObservation",
    "PolicyAction",
    "PolicyError",
    "policy_array",
    "policy_command",
    "network_action",
    "ACTIVATIONS",
]

#: the activations between the layers (the code of each is its index)
ACTIVATIONS = ("tanh", "relu")
#: the codes of the activations and of the action types (their index in ACTIVATIONS and
#: in ACTION_TYPES) in the parameter array
CODE_TANH = ACTIVATIONS.index("tanh")
CODE_SETPOINTS = ACTION_TYPES.index("setpoints")

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

# -- the compiled law --------------------------------------------------------------------


@kernel
def _layers_start(params):
    """The first slot of the layers' weights in ``params``."""
    return P_WIDTHS + int(params[P_N_LAYERS]) + 1


@kernel(inline="always")
def _clamp(v, lo, hi):
    """``v`` clipped to [lo, hi] (NaN stays NaN)."""
    if v < lo:
        return lo
    if v > hi:
        return hi
    return v


@kernel
def network_action(y, params, scratch, action):
    """The policy's action (in its own units, clipped to its box) for the readings ``y``
    (slots of :mod:`scoutsim.control.sensors`, SI) into ``action``; ``scratch``: 2 x
    ``P_MAX_WIDTH`` floats. The observation (float32, clipped to its box), its
    normalisation and the network as the module docstring says."""
    width = int(params[P_MAX_WIDTH])
    a = scratch[:width]
    b = scratch[width : 2 * width]
    normalised = params[P_NORMALISED] != 0.0
    clip = params[P_OBS_CLIP]
    for i in range(N_SENSORS):
        o = _clamp(np.float64(np.float32(y[i])), params[P_OBS_LOW + i], params[P_OBS_HIGH + i])
        if normalised:
            o = _clamp((o - params[P_OBS_MEAN + i]) / params[P_OBS_STD + i], -clip, clip)
        a[i] = o
    n_layers = int(params[P_N_LAYERS])
    tanh = int(params[P_ACTIVATION]) == CODE_TANH
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
        action[i] = _clamp(a[i], params[P_ACTION_LOW + i], params[P_ACTION_HIGH + i])


def policy_command(t, y, params, state, torque, leg_states):
    """One control sample of the policy (see the module docstring): at a policy tick the
    action from the readings ``y`` is computed and held (``state[S_ACTION:]``; set-points
    also into the state's Table I array); then the torques of the held action, or of the
    Table I law with the held set-points, per physical leg [N m]. Returns 0."""
    k = int(state[S_SAMPLE])
    setpoints = int(params[P_ACTION_TYPE]) == CODE_SETPOINTS
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


class PolicyController(CompiledController):
    """A learned feed-forward policy run as a controller, compiled into the simulator's
    loop (see the module docstring for what it computes).

    Parameters
    ----------
    layers : sequence of (weights, biases)
        The Linear layers in order, the output layer last: ``weights`` (out, in) and
        ``biases`` (out,) as PyTorch's ``nn.Linear`` keeps them; the first takes the
        ``N_SENSORS`` readings, the last gives the action.
    observation : PolicyObservation
        The observation box and the normalisation (the environment's observation space,
        ``VecNormalize``'s statistics).
    action : PolicyAction
        The action's type ("torque" or "setpoints"), entries, box and map to physical
        units (the environment's ``action_center`` and ``action_half_width``).
    activation : {"tanh", "relu"}
        After every layer but the last (Stable-Baselines3's ``MlpPolicy``: tanh).
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
        How errors and a run's provenance name it (default "PolicyController").

    Attributes
    ----------
    samples_per_step : int
        Control samples per policy step.
    params : the parameter array packed with Scout II's constants (:func:`policy_array`);
        a run packs its robot's (:meth:`params_for`).

    The action is the file's map, the environment's at training: on another robot or model
    the policy meets that plant with the torques or set-points it learned (a set-point
    policy's Table I array packs the run's robot's constants, as Table I does).
    Picklable (its arrays travel; the compiled function is compiled once per process).
    """

    def __init__(
        self,
        layers: Sequence,
        observation: PolicyObservation,
        action: PolicyAction,
        *,
        activation: str = "tanh",
        policy_period: float = 0.01,
        controller_parameters: ControllerParameters | None = None,
        metadata: dict | None = None,
        name: str | None = None,
    ):
        if activation not in ACTIVATIONS:
            raise PolicyError(
                f"activation = {activation!r} is not allowed: must be one of {list(ACTIVATIONS)}",
                "activation",
            )
        for value, kind, what in (
            (observation, PolicyObservation, "observation"),
            (action, PolicyAction, "action"),
            (
                controller_parameters or ControllerParameters(),
                ControllerParameters,
                "controller_parameters",
            ),
        ):
            if not isinstance(value, kind):
                raise PolicyError(
                    f"{what} must be {kind.__name__}, not {type(value).__name__}", what
                )
        self.activation = activation
        self.observation = observation
        self.action = action
        self.layers = _check_layers(layers, len(action.names))
        cparams = controller_parameters or ControllerParameters()
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
        width = max([N_SENSORS] + [w.shape[0] for w, _ in self.layers])
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

    # -- the policy from Python ------------------------------------------------------------

    def predict(self, observation) -> np.ndarray:
        """The policy's deterministic action (in its own units, clipped to its box; float64)
        for an observation or sensor readings ((N_SENSORS,) or a batch (n, N_SENSORS)),
        computed with NumPy: as Stable-Baselines3's
        ``model.predict(vec_normalize.normalize_obs(obs), deterministic=True)``."""
        x = self.observation.normalise(self.observation.observe(observation))
        for i, (w, b) in enumerate(self.layers):
            x = x @ w.T + b
            if i < len(self.layers) - 1:
                x = np.tanh(x) if self.activation == "tanh" else np.maximum(x, 0.0)
        return np.clip(x, self.action.low, self.action.high)

    def physical_action(self, observation) -> np.ndarray:
        """The physical action [N m per leg, or rad] of :meth:`predict`'s action."""
        return self.action.physical(self.predict(observation))

    def compiled_action(self, readings) -> np.ndarray:
        """The action (in the policy's own units, as :meth:`predict`) for the sensor
        readings ``readings`` ((N_SENSORS,), SI) computed by the compiled evaluation the
        command runs at a policy tick (:func:`network_action`), not by NumPy."""
        y = np.array(readings, dtype=np.float64).reshape(N_SENSORS)
        out = np.zeros(len(self.action.names))
        network_action(y, self.params, np.zeros(2 * int(self.params[P_MAX_WIDTH])), out)
        return out

    @property
    def held_action(self) -> np.ndarray | None:
        """The physical action [N m per leg, or rad] held by the compiled command after the
        last :meth:`command` call from Python (None before the first); a run's own is in
        the run's controller state."""
        state = getattr(self, "_py_state", None)
        if state is None:
            return None
        return state[S_ACTION : S_ACTION + len(self.action.names)].copy()

    # -- the file --------------------------------------------------------------------------

    def save(self, path) -> None:
        """Write the policy to ``path`` (``.npz``; fields
        :data:`~scoutsim.control.policy_file.FILE_FIELDS`); :meth:`load` reads it back,
        every array bit for bit."""
        assert self.controller_parameters is not None  # (set by the constructor)
        write_policy_file(
            path,
            self.layers,
            self.activation,
            self.observation,
            self.action,
            policy_period=self.policy_period,
            controller_parameters=self.controller_parameters,
            metadata=self.metadata,
        )

    @classmethod
    def load(cls, path) -> PolicyController:
        """The policy of the file ``path`` (as :meth:`save` writes it, or
        :func:`scoutsim.envs.policy_export.export_policy`), named after the file
        (``PolicyController(policy.npz)``: how errors and a run's provenance name it).
        PolicyError naming the file and the field if a field is missing or not allowed
        (shapes, values)."""
        pieces = read_policy_file(path)
        try:
            return cls(**pieces, name=f"PolicyController({_basename(path)})")
        except PolicyError as exc:
            raise PolicyError(f"policy file {str(path)!r}: {exc}", exc.field) from None

    def __repr__(self):
        widths = [N_SENSORS] + [w.shape[0] for w, _ in self.layers]
        return (
            f"PolicyController({self.action.type}, layers {'-'.join(map(str, widths))} "
            f"{self.activation}, "
            f"{'normalised' if self.observation.normalised else 'raw'} observation, "
            f"policy period {self.policy_period:g} s)"
        )


def _basename(path) -> str:
    return os.path.basename(os.fspath(path))


def _check_layers(layers, n_actions: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """The layers as float64 (weights (out, in), biases (out,)), checked: finite, each
    layer's input the last one's output, the first's the N_SENSORS readings, the last's
    output the action's ``n_actions`` entries."""
    try:
        pairs = list(layers)
    except TypeError:
        raise PolicyError("layers must be a sequence of (weights, biases)", "layers") from None
    if not pairs:
        raise PolicyError("layers is empty: give at least the output layer", "layers")
    out: list[tuple[np.ndarray, np.ndarray]] = []
    n_in = N_SENSORS
    for i, pair in enumerate(pairs):
        try:
            w, b = pair
        except (TypeError, ValueError):
            raise PolicyError(
                f"layer {i} must be a pair (weights, biases)", f"weights_{i}"
            ) from None
        w = checked_array(w, f"weights_{i}")
        b = checked_array(b, f"biases_{i}")
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
    if n_in != n_actions:
        raise PolicyError(
            f"weights_{len(pairs) - 1} gives {n_in} outputs: the action has {n_actions} "
            "entries (action_center)",
            f"weights_{len(pairs) - 1}",
        )
    return out


def policy_array(policy: PolicyController, robot: RobotParameters | None = None) -> np.ndarray:
    """The parameter array of ``policy``'s compiled command (slots ``P_*``, module
    docstring) for a run of ``robot`` (default Scout II): its Table I array packed with that
    robot's constants."""
    obs, act = policy.observation, policy.action
    n_actions = len(act.names)
    widths = [N_SENSORS] + [w.shape[0] for w, _ in policy.layers]
    size = P_WIDTHS + len(widths) + sum(w.size + b.size for w, b in policy.layers)
    a = np.zeros(size)
    a[P_ACTION_TYPE] = ACTION_TYPES.index(act.type)
    a[P_SAMPLES_PER_STEP] = policy.samples_per_step
    a[P_ACTIVATION] = ACTIVATIONS.index(policy.activation)
    a[P_NORMALISED] = 1.0 if obs.normalised else 0.0
    a[P_OBS_CLIP] = obs.clip
    a[P_N_ACTIONS] = n_actions
    a[P_N_LAYERS] = len(policy.layers)
    a[P_MAX_WIDTH] = max(widths)
    a[P_TABLE_I : P_TABLE_I + NC] = controller_array(policy.controller_parameters, robot)
    a[P_OBS_LOW : P_OBS_LOW + N_SENSORS] = obs.low
    a[P_OBS_HIGH : P_OBS_HIGH + N_SENSORS] = obs.high
    if obs.normalised:
        a[P_OBS_MEAN : P_OBS_MEAN + N_SENSORS] = obs.mean
        a[P_OBS_STD : P_OBS_STD + N_SENSORS] = obs.std
    for slot, values in (
        (P_ACTION_LOW, act.low),
        (P_ACTION_HIGH, act.high),
        (P_ACTION_CENTER, act.center),
        (P_ACTION_HALF_WIDTH, act.half_width),
        (P_ACTION_SLOT, act.slots),
    ):
        a[slot : slot + n_actions] = values
    a[P_WIDTHS : P_WIDTHS + len(widths)] = widths
    at = P_WIDTHS + len(widths)
    for w, b in policy.layers:
        a[at : at + w.size] = w.ravel()
        at += w.size
        a[at : at + b.size] = b
        at += b.size
    return a
