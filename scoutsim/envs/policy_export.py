"""A policy trained with Stable-Baselines3 on ``scoutsim/Bound-v0``, exported to a policy
file that :class:`~scoutsim.control.policy.PolicyController` runs as a controller
(:func:`export_policy`)::

    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize
    from scoutsim.envs.policy_export import export_policy

    model = PPO.load("ppo_bound.zip")
    vec_normalize = VecNormalize.load("vec_normalize.pkl", venv)   # if trained with it
    export_policy(model, "policy.npz", vec_normalize=vec_normalize, env=venv)

What is read: the actor of the model's policy (an ``ActorCriticPolicy``, e.g. PPO's or
A2C's ``MlpPolicy``: the Linear layers of ``mlp_extractor.policy_net``, their activation,
then ``action_net``; the deterministic action is its output, the Gaussian's mean), the
observation normalisation of ``VecNormalize`` (``obs_rms.mean``, ``obs_rms.var``,
``epsilon``, ``clip_obs``; none when it was made with ``norm_obs=False``), and of the
environment (:class:`~scoutsim.envs.bound.BoundEnv`): the observation box, the action type
and its map to physical units (``action_center``, ``action_half_width``), the policy
period, the Table I parameters, and the model and robot it simulated (as metadata).

PyTorch is imported by :func:`export_policy` only (it reads the model's modules):
importing this module (or scoutsim) needs neither PyTorch nor Stable-Baselines3, and nothing of them is needed to run the exported
policy.
"""

from __future__ import annotations

import dataclasses
import importlib
from importlib.metadata import PackageNotFoundError, version
from typing import Any

import numpy as np

from .._version import __version__
from ..control.policy import (
    ACTIVATIONS,
    PolicyAction,
    PolicyController,
    PolicyError,
    PolicyObservation,
)
from .configuration import SETPOINTS

__all__ = ["export_policy"]

#: PyTorch activation module -> the policy's activation name
_ACTIVATION_MODULES = {"Tanh": "tanh", "ReLU": "relu"}


def export_policy(
    model,
    path,
    *,
    env=None,
    vec_normalize=None,
    metadata: dict | None = None,
) -> PolicyController:
    """Export the deterministic policy of the Stable-Baselines3 ``model`` to the policy
    file ``path`` (``.npz``) and return it as a :class:`PolicyController`.

    Parameters
    ----------
    model : a Stable-Baselines3 model with an ``ActorCriticPolicy`` (PPO, A2C; ``MlpPolicy``)
        and a Box action space, trained on ``scoutsim/Bound-v0``.
    path : where to write the policy file (a name ending in ``.npz``).
    env : the environment it was trained on: a :class:`~scoutsim.envs.bound.BoundEnv`,
        possibly wrapped, or a vector environment of them (``DummyVecEnv``,
        ``SubprocVecEnv``, ``VecNormalize``); default: ``vec_normalize``, else
        ``model.get_env()``.
    vec_normalize : the ``VecNormalize`` the model was trained behind (its observation
        statistics); default: the one ``env`` or ``model.get_env()`` is wrapped in, if
        any. Its reward normalisation does not concern the policy.
    metadata : facts of your own to keep in the file (JSON-safe), e.g. the training's
        seed and steps.

    Raises
    ------
    PolicyError : a policy or environment this cannot export (which, and why).
    """
    policy = model.policy
    layers, activation = _actor_layers(policy)
    venv = (
        env if env is not None else vec_normalize if vec_normalize is not None else model.get_env()
    )
    if venv is None:
        raise PolicyError(
            "export_policy needs the environment the model was trained on: give env= "
            "(a BoundEnv or a vector environment of them)",
            "env",
        )
    if vec_normalize is None:
        vec_normalize = _find_vec_normalize(venv) or _find_vec_normalize(model.get_env())
    facts = _environment_facts(venv)
    low, high = facts["observation_low"], facts["observation_high"]
    observation_space = policy.observation_space
    if tuple(observation_space.shape) != low.shape:
        raise PolicyError(
            f"the policy's observation space has shape {observation_space.shape}, the "
            f"environment's {low.shape}: export the policy with the environment it was "
            "trained on",
            "env",
        )
    normalisation: dict[str, Any] = {}
    if vec_normalize is not None and getattr(vec_normalize, "norm_obs", False):
        rms = vec_normalize.obs_rms
        if isinstance(rms, dict):
            raise PolicyError(
                "VecNormalize of a dictionary observation: scoutsim/Bound-v0's "
                "observation is one array",
                "vec_normalize",
            )
        normalisation = dict(
            mean=np.asarray(rms.mean, dtype=np.float64),
            var=np.asarray(rms.var, dtype=np.float64),
            epsilon=float(vec_normalize.epsilon),
            clip=float(vec_normalize.clip_obs),
        )
    action_space = policy.action_space
    # the box the model's predict() clips its action to, and the environment's map
    box_low = np.asarray(action_space.low, dtype=np.float64)
    box_high = np.asarray(action_space.high, dtype=np.float64)
    center, half = facts["action_center"], facts["action_half_width"]
    if facts["normalize_actions"]:
        box_low, box_high = np.maximum(box_low, -1.0), np.minimum(box_high, 1.0)
    else:  # (the action is physical, clipped to the environment's range: used as it is)
        box_low, box_high = np.maximum(box_low, center - half), np.minimum(box_high, center + half)
        center, half = np.zeros_like(center), np.ones_like(half)
    info = {
        "environment": "scoutsim/Bound-v0",
        "model": facts["model"],
        "robot": facts["robot"],
        "observation_names": facts["observation_names"],
        "trained_with": f"stable-baselines3 {_version('stable-baselines3')}, "
        f"{type(model).__name__} {type(policy).__name__}",
        "training_steps": int(getattr(model, "num_timesteps", 0)),
        "exported_by": f"scoutsim {__version__}",
    }
    exported = PolicyController(
        layers,
        PolicyObservation(low=low, high=high, **normalisation),
        PolicyAction(
            type=facts["action_type"],
            center=center,
            half_width=half,
            low=box_low,
            high=box_high,
            names=SETPOINTS if facts["action_type"] == "setpoints" else (),
        ),
        activation=activation,
        policy_period=facts["policy_period"],
        controller_parameters=facts["controller"],
        metadata={**info, **(metadata or {})},
    )
    exported.save(path)
    return exported


def _actor_layers(policy) -> tuple[list[tuple[np.ndarray, np.ndarray]], str]:
    """The actor's Linear layers (weights, biases as float64) and their activation."""
    from gymnasium import spaces

    # (PyTorch: imported here only; its module by name, so scoutsim's type check needs no
    # PyTorch installed)
    nn = importlib.import_module("torch.nn")

    name = type(policy).__name__
    mlp = getattr(getattr(policy, "mlp_extractor", None), "policy_net", None)
    head = getattr(policy, "action_net", None)
    if not isinstance(mlp, nn.Sequential) or not isinstance(head, nn.Linear):
        raise PolicyError(
            f"{name} is not an actor-critic MLP policy (mlp_extractor.policy_net and "
            "action_net): export a PPO or A2C model with MlpPolicy",
            "model",
        )
    if not isinstance(policy.action_space, spaces.Box):
        raise PolicyError(
            f"{name} acts in {policy.action_space}: scoutsim/Bound-v0's actions are a Box",
            "model",
        )
    if getattr(policy, "squash_output", False):
        raise PolicyError(
            f"{name} squashes its output (use_sde with squash_output=True): the exported "
            "policy runs the Gaussian's mean, clipped to the box; train without squashing",
            "model",
        )
    extractor = getattr(policy, "pi_features_extractor", None)
    if type(extractor).__name__ != "FlattenExtractor":
        raise PolicyError(
            f"{name}'s features extractor is {type(extractor).__name__}: the exported "
            "policy reads the observation as it is (FlattenExtractor, MlpPolicy's)",
            "model",
        )
    hidden = list(mlp)
    layers: list[tuple[np.ndarray, np.ndarray]] = []
    activations = set()
    for i, m in enumerate(hidden):
        linear = i % 2 == 0
        if linear and isinstance(m, nn.Linear) and i + 1 < len(hidden):
            layers.append(_linear(m, name, len(layers)))
        elif not linear and type(m).__name__ in _ACTIVATION_MODULES:
            activations.add(_ACTIVATION_MODULES[type(m).__name__])
        else:
            raise PolicyError(
                f"{name}: mlp_extractor.policy_net is not Linear layers each followed by "
                f"one of {sorted(_ACTIVATION_MODULES)} (found {type(m).__name__} at "
                f"position {i})",
                "model",
            )
    layers.append(_linear(head, name, len(layers)))
    if len(activations) > 1:
        raise PolicyError(f"{name} mixes activations {sorted(activations)}", "model")
    activation = activations.pop() if activations else ACTIVATIONS[0]
    return layers, activation


def _version(package: str) -> str:
    try:
        return version(package)
    except PackageNotFoundError:
        return "(version unknown)"


def _linear(m, name: str, index: int) -> tuple[np.ndarray, np.ndarray]:
    """(weights, biases) of the PyTorch Linear layer ``m`` as float64 arrays."""
    if m.bias is None:
        raise PolicyError(f"{name}: layer {index} has no bias", "model")
    return (
        m.weight.detach().cpu().numpy().astype(np.float64),
        m.bias.detach().cpu().numpy().astype(np.float64),
    )


def _find_vec_normalize(venv):
    """The VecNormalize ``venv`` is or wraps (through ``.venv``), or None."""
    while venv is not None:
        if type(venv).__name__ == "VecNormalize" or hasattr(venv, "obs_rms"):
            return venv
        venv = getattr(venv, "venv", None)
    return None


def _environment_facts(env) -> dict:
    """What the policy needs of the BoundEnv ``env`` (or of the first environment of a
    vector environment)."""
    if hasattr(env, "get_attr") and hasattr(env, "num_envs"):  # a Stable-Baselines3 VecEnv

        def get(name):
            return env.get_attr(name, indices=[0])[0]
    else:
        base = getattr(env, "unwrapped", env)

        def get(name):
            return getattr(base, name)

    try:
        box = get("observation_space")
        facts = {
            "action_type": get("action_type"),
            "policy_period": float(get("policy_period")),
            "controller": get("controller"),
            "model": get("model"),
            "robot": dataclasses.asdict(get("robot")),
            "action_center": np.asarray(get("action_center"), dtype=np.float64),
            "action_half_width": np.asarray(get("action_half_width"), dtype=np.float64),
            "normalize_actions": bool(get("normalize_actions")),
            "observation_names": list(get("observation_names")),
        }
    except AttributeError as exc:
        raise PolicyError(
            f"the environment is not scoutsim/Bound-v0 (BoundEnv): {exc}", "env"
        ) from None
    facts["observation_low"] = np.asarray(box.low, dtype=np.float32)
    facts["observation_high"] = np.asarray(box.high, dtype=np.float32)
    return facts
