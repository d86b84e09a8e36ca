"""The policy file: a learned policy (:class:`~scoutsim.control.policy.PolicyController`)
kept in a NumPy ``.npz`` archive of plain arrays (no pickled objects), one field per fact
(:data:`FILE_FIELDS`): the layers, the activation, the observation box and normalisation,
the action's type, entries, box and map, the policy period, the Table I parameters and the
metadata (JSON). :func:`write_policy_file` writes one, :func:`read_policy_file` reads and
checks one, naming the file and the field that is wrong.
"""

from __future__ import annotations

import dataclasses
import json
import os

import numpy as np

from ..io.run_directory import atomic_write
from ..parameters import ControllerParameters, ParameterError
from .policy_spaces import ACTION_TYPES, PolicyAction, PolicyError, PolicyObservation
from .sensors import N_SENSORS

__all__ = ["FILE_FORMAT", "FILE_FIELDS", "write_policy_file", "read_policy_file"]

#: what a policy file says it is (its ``format`` field)
FILE_FORMAT = "scoutsim.policy/1"

#: the fields of a policy file (``{i}`` a layer's index, 0 the first): name -> what it holds
FILE_FIELDS = {
    "format": f'"{FILE_FORMAT}"',
    "weights_{i}": "layer i's weights, (out, in), float64",
    "biases_{i}": "layer i's biases, (out,), float64",
    "activation": 'between the layers: "tanh" or "relu"',
    "observation_low": f"the observation box's low end, ({N_SENSORS},) float32",
    "observation_high": f"the observation box's high end, ({N_SENSORS},) float32",
    "observation_mean": f"(optional) the normalisation's running mean, ({N_SENSORS},) float64",
    "observation_var": f"(optional) its running variance, ({N_SENSORS},) float64",
    "observation_epsilon": "(with the mean) added to the variance",
    "observation_clip": "(with the mean) the normalised observation's clip",
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


def write_policy_file(
    path,
    layers,
    activation: str,
    observation: PolicyObservation,
    action: PolicyAction,
    *,
    policy_period: float,
    controller_parameters: ControllerParameters,
    metadata: dict,
) -> None:
    """Write a policy file (``.npz``) of these pieces to ``path`` (atomically: a file cut
    off while writing is never left under the name)."""
    path = os.fspath(path)
    if not path.endswith(".npz"):
        raise PolicyError(f"a policy file's name ends in .npz, not {path!r}", "path")
    assert action.low is not None and action.high is not None  # (set by PolicyAction)
    fields: dict[str, np.ndarray] = {
        "format": np.array(FILE_FORMAT),
        "activation": np.array(activation),
        "observation_low": observation.low,
        "observation_high": observation.high,
        "action_type": np.array(action.type),
        "action_names": np.array(action.names),
        "action_low": action.low,
        "action_high": action.high,
        "action_center": action.center,
        "action_half_width": action.half_width,
        "policy_period": np.array(float(policy_period)),
        "controller_parameters": np.array(json.dumps(dataclasses.asdict(controller_parameters))),
        "metadata": np.array(json.dumps(metadata, sort_keys=True)),
    }
    if observation.normalised:
        assert observation.mean is not None and observation.var is not None
        fields.update(
            observation_mean=observation.mean,
            observation_var=observation.var,
            observation_epsilon=np.array(observation.epsilon),
            observation_clip=np.array(observation.clip),
        )
    for i, (w, b) in enumerate(layers):
        fields[f"weights_{i}"] = w
        fields[f"biases_{i}"] = b
    atomic_write(path, lambda tmp: np.savez(tmp, allow_pickle=False, **fields))


def read_policy_file(path) -> dict:
    """The pieces of the policy file ``path``, checked, as keywords of
    :class:`~scoutsim.control.policy.PolicyController` (``layers``, ``activation``,
    ``observation``, ``action``, ``policy_period``, ``controller_parameters``,
    ``metadata``). PolicyError naming the file and the field otherwise."""
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
        return _pieces(fields)
    except PolicyError as exc:
        raise PolicyError(f"policy file {path!r}: {exc}", exc.field) from None


def _pieces(f: dict) -> dict:
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

    def json_object(name) -> dict:
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
    layers: list[tuple[np.ndarray, np.ndarray]] = []
    while f"weights_{len(layers)}" in f or f"biases_{len(layers)}" in f:
        i = len(layers)
        layers.append((need(f"weights_{i}"), need(f"biases_{i}")))
    if not layers:
        raise PolicyError("field 'weights_0' is missing (the first layer)", "weights_0")
    stray = sorted(
        k for k in f if k.startswith(("weights_", "biases_")) and not _layer_key(k, len(layers))
    )
    if stray:
        raise PolicyError(f"fields {stray} do not follow layers 0 .. {len(layers) - 1}", stray[0])
    try:
        cparams = ControllerParameters(**json_object("controller_parameters"))
    except (TypeError, ParameterError) as exc:
        raise PolicyError(
            f"field 'controller_parameters' is not allowed: {exc}", "controller_parameters"
        ) from None
    normalised = "observation_mean" in f or "observation_var" in f
    names = need("action_names")
    if names.ndim != 1 or names.dtype.kind != "U":
        raise PolicyError("field 'action_names' must be a list of strings", "action_names")
    observation = PolicyObservation(
        low=need("observation_low"),
        high=need("observation_high"),
        mean=need("observation_mean") if normalised else None,
        var=need("observation_var") if normalised else None,
        epsilon=number("observation_epsilon") if normalised else 1e-8,
        clip=number("observation_clip") if normalised else 10.0,
    )
    action = PolicyAction(
        type=text("action_type"),
        center=need("action_center"),
        half_width=need("action_half_width"),
        low=need("action_low"),
        high=need("action_high"),
        names=tuple(str(n) for n in names),
    )
    return dict(
        layers=layers,
        activation=text("activation"),
        observation=observation,
        action=action,
        policy_period=number("policy_period"),
        controller_parameters=cparams,
        metadata=json_object("metadata"),
    )


def _layer_key(key: str, n_layers: int) -> bool:
    """``key`` is ``weights_{i}`` or ``biases_{i}`` of a layer 0 .. n_layers - 1."""
    index = key.partition("_")[2]
    return index.isdigit() and str(int(index)) == index and int(index) < n_layers
