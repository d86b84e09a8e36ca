"""What a learned policy sees and what its output means: :class:`PolicyObservation` (the
observation box and the normalisation of the sensor readings) and :class:`PolicyAction`
(the action's type and entries, the box its output is clipped to and the map to physical
units), as the learning environment ``scoutsim/Bound-v0`` defined them when the policy was
trained (:class:`~scoutsim.control.policy.PolicyController` runs them).

A value that is not allowed raises :class:`PolicyError`, naming the field.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .bounding import SCHEDULABLE
from .sensors import N_SENSORS

__all__ = [
    "PolicyObservation",
    "PolicyAction",
    "PolicyError",
    "ACTION_TYPES",
    "TORQUE_NAMES",
    "MAX_ACTIONS",
]

#: what an action is: the hip torques, or set-points of the Table I controller
ACTION_TYPES = ("torque", "setpoints")
#: the names of a torque action's entries: the hip torques [N m], back then front
TORQUE_NAMES = ("hip_torque_back", "hip_torque_front")
#: the most entries an action may have (the four set-points)
MAX_ACTIONS = len(SCHEDULABLE)


class PolicyError(ValueError):
    """A policy (its arrays, or a policy file) that is not allowed: the message names the
    field and what it must be; ``field`` is its name."""

    def __init__(self, message: str, field: str | None = None):
        super().__init__(message)
        self.field = field


def checked_array(value, name: str, *, shape=None, dtype=np.float64, finite=True) -> np.ndarray:
    """``value`` as a new array of ``dtype`` (and ``shape``), without NaN (and, if
    ``finite``, without infinities); PolicyError naming ``name`` otherwise."""
    try:
        a = np.array(value, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise PolicyError(f"{name} is not allowed: not an array of numbers ({exc})", name) from None
    if shape is not None and a.shape != tuple(shape):
        raise PolicyError(f"{name} has shape {a.shape}: must be {tuple(shape)}", name)
    if np.isnan(a).any() or (finite and not np.isfinite(a).all()):
        what = "finite" if finite else "a number (not NaN)"
        raise PolicyError(f"{name} is not allowed: every entry must be {what}", name)
    return a


def positive(value, name: str) -> float:
    """``value`` as a finite float > 0; PolicyError naming ``name`` otherwise."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    if not (math.isfinite(v) and v > 0):
        raise PolicyError(f"{name} = {value!r} is not allowed: must be a finite number > 0", name)
    return v


@dataclass(frozen=True, eq=False)
class PolicyObservation:
    """What the policy sees of the sensor readings (slots :mod:`scoutsim.control.sensors`,
    ``N_SENSORS`` of them, SI): the readings cast to float32 and clipped to the box
    ``low`` .. ``high``, then, if ``mean`` is given, normalised as Stable-Baselines3's
    ``VecNormalize`` does: ``clip((obs - mean) / sqrt(var + epsilon), -clip, clip)``.

    Attributes
    ----------
    low, high : (N_SENSORS,) float32
        The observation box (the environment's observation space), in each slot's SI
        unit; infinite ends are allowed.
    mean, var : (N_SENSORS,) float64, or None
        The running mean and variance of the observation (``VecNormalize.obs_rms``),
        frozen at export; None (both): the observation is not normalised.
    epsilon : float
        Added to the variance (``VecNormalize.epsilon``, default 1e-8).
    clip : float
        The normalised observation's clip (``VecNormalize.clip_obs``, default 10).
    """

    low: np.ndarray
    high: np.ndarray
    mean: np.ndarray | None = None
    var: np.ndarray | None = None
    epsilon: float = 1e-8
    clip: float = 10.0

    def __post_init__(self):
        shape = (N_SENSORS,)
        low = checked_array(
            self.low, "observation_low", shape=shape, dtype=np.float32, finite=False
        )
        high = checked_array(
            self.high, "observation_high", shape=shape, dtype=np.float32, finite=False
        )
        if (low > high).any():
            raise PolicyError(
                "observation_low is not allowed: above observation_high in slots "
                f"{np.flatnonzero(low > high).tolist()}",
                "observation_low",
            )
        if (self.mean is None) != (self.var is None):
            raise PolicyError(
                "observation_mean and observation_var go together: give both (a normalised "
                "observation) or neither",
                "observation_mean" if self.mean is None else "observation_var",
            )
        mean = var = None
        if self.mean is not None:
            mean = checked_array(self.mean, "observation_mean", shape=shape)
            var = checked_array(self.var, "observation_var", shape=shape)
            if (var < 0).any():
                raise PolicyError("observation_var is not allowed: must be >= 0", "observation_var")
        set_ = object.__setattr__
        for name, value in (("low", low), ("high", high), ("mean", mean), ("var", var)):
            if value is not None:
                value.flags.writeable = False
            set_(self, name, value)
        set_(self, "epsilon", positive(self.epsilon, "observation_epsilon"))
        set_(self, "clip", positive(self.clip, "observation_clip"))

    @property
    def normalised(self) -> bool:
        """True if the observation is normalised (a policy trained with VecNormalize)."""
        return self.mean is not None

    @property
    def std(self) -> np.ndarray:
        """sqrt(var + epsilon), what a normalised observation is divided by (ones if it
        is not normalised)."""
        if self.var is None:
            return np.ones(N_SENSORS)
        return np.sqrt(self.var + self.epsilon)

    def observe(self, readings) -> np.ndarray:
        """The observation (float32, clipped to the box) of the readings ``readings``
        ((N_SENSORS,) or (n, N_SENSORS), SI), as the environment hands them to the agent."""
        return np.clip(np.asarray(readings).astype(np.float32), self.low, self.high)

    def normalise(self, observation) -> np.ndarray:
        """The network's input (float64) for an observation: normalised and clipped, or as
        it is."""
        x = np.asarray(observation, dtype=np.float64)
        if self.mean is None:
            return x
        return np.clip((x - self.mean) / self.std, -self.clip, self.clip)


@dataclass(frozen=True, eq=False)
class PolicyAction:
    """What the policy's output means. The output is clipped to ``low`` .. ``high`` (-1 ..
    1: the environment's normalised actions, what ``model.predict`` does for a Box action
    space), then made physical: ``center + half_width * action``.

    Attributes
    ----------
    type : {"torque", "setpoints"}
        "torque": the hip torques (back, front) [N m per physical leg, at the leg], held
        for the policy step; "setpoints": set-points of the Table I controller [rad], which
        runs at every sample with them.
    center, half_width : (n,) float64
        The map to physical units [N m or rad] (the environment's ``action_center`` and
        ``action_half_width``).
    low, high : (n,) float64, optional
        The box the output is clipped to (default -1 and 1).
    names : sequence of str, optional
        The entries: for torques :data:`TORQUE_NAMES` (the default); for set-points
        fields of :data:`~scoutsim.control.bounding.SCHEDULABLE` (default: all four in its
        order, the environment's ``SETPOINTS``).
    """

    type: str
    center: np.ndarray
    half_width: np.ndarray
    low: np.ndarray | None = None
    high: np.ndarray | None = None
    names: tuple = field(default=())

    def __post_init__(self):
        if self.type not in ACTION_TYPES:
            raise PolicyError(
                f"action_type = {self.type!r} is not allowed: must be one of {list(ACTION_TYPES)}",
                "action_type",
            )
        center = checked_array(self.center, "action_center")
        if center.ndim != 1 or not 1 <= center.size <= MAX_ACTIONS:
            raise PolicyError(
                f"action_center has shape {center.shape}: must be (n,), n = 1 .. {MAX_ACTIONS}",
                "action_center",
            )
        shape = center.shape
        half = checked_array(self.half_width, "action_half_width", shape=shape)
        ones = np.ones(shape)
        low = checked_array(-ones if self.low is None else self.low, "action_low", shape=shape)
        high = checked_array(ones if self.high is None else self.high, "action_high", shape=shape)
        if (low > high).any():
            raise PolicyError("action_low is not allowed: above action_high", "action_low")
        set_ = object.__setattr__
        for name, value in (("center", center), ("half_width", half), ("low", low), ("high", high)):
            value.flags.writeable = False
            set_(self, name, value)
        set_(self, "names", _names(self.names, self.type, center.size))

    @property
    def slots(self) -> list[int]:
        """Where each entry goes: the leg of a torque (0 back, 1 front), or the Table I
        controller array's slot of a set-point (``C_*``)."""
        if self.type == "torque":
            return [TORQUE_NAMES.index(n) for n in self.names]
        return [SCHEDULABLE[n] for n in self.names]

    def physical(self, output) -> np.ndarray:
        """The physical action [N m or rad] of the network's ``output`` (clipped first)."""
        return self.center + self.half_width * np.clip(output, self.low, self.high)


def _names(names, action_type: str, n: int) -> tuple[str, ...]:
    """The action's entries (see :class:`PolicyAction`), checked against its type and
    length."""
    allowed = TORQUE_NAMES if action_type == "torque" else tuple(SCHEDULABLE)
    names = tuple(str(x) for x in names) if len(names) else allowed
    ok = len(names) == n and len(set(names)) == n and set(names) <= set(allowed)
    if action_type == "torque":
        ok = ok and names == TORQUE_NAMES
    if not ok:
        what = (
            f"{list(TORQUE_NAMES)}"
            if action_type == "torque"
            else f"{n} distinct set-points of {list(SCHEDULABLE)}"
        )
        raise PolicyError(
            f"action_names = {list(names)} is not allowed: a {action_type} action of {n} "
            f"entries names {what}",
            "action_names",
        )
    return names
