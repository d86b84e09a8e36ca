"""The reward and the termination settings of ``scoutsim/Bound-v0``
(:class:`~scoutsim.envs.bound.BoundEnv`): the bundle :class:`Reward` of its weights and
health ranges, each field also a keyword of the environment.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


def health_range(pair, name: str) -> tuple[float, float]:
    """The range (min, max) given as ``pair`` (the field ``name``), or a clear error."""
    try:
        lo, hi = (float(v) for v in pair)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {pair!r} is not allowed: must be (min, max)") from None
    if math.isnan(lo) or math.isnan(hi) or lo > hi:
        raise ValueError(f"{name} = {pair!r} is not allowed: must be (min, max), min <= max")
    return lo, hi


@dataclass(frozen=True)
class Reward:
    """The reward and the termination of :class:`~scoutsim.envs.bound.BoundEnv` (each field is also a keyword of
    the environment, which overrides the bundle's): ``forward_reward_weight``,
    ``target_speed`` [m/s] (None: reward speed itself), ``energy_cost_weight`` [1/J],
    ``healthy_reward``, ``terminate_when_fallen``, ``healthy_height_range`` [m],
    ``healthy_pitch_range`` [rad] (see :class:`~scoutsim.envs.bound.BoundEnv`)."""

    forward_reward_weight: float = 1.0
    target_speed: float | None = None
    energy_cost_weight: float = 0.01
    healthy_reward: float = 1.0
    terminate_when_fallen: bool = True
    healthy_height_range: tuple = (0.2, math.inf)
    healthy_pitch_range: tuple = (-math.radians(30.0), math.radians(30.0))


def check_weights(reward: Reward) -> None:
    """Refuse a reward weight that is not a finite number and a target speed that is not
    finite (or None), naming the field."""
    forward_reward_weight, target_speed, energy_cost_weight, healthy_reward = (
        reward.forward_reward_weight,
        reward.target_speed,
        reward.energy_cost_weight,
        reward.healthy_reward,
    )
    for name, v in (
        ("forward_reward_weight", forward_reward_weight),
        ("energy_cost_weight", energy_cost_weight),
        ("healthy_reward", healthy_reward),
    ):
        if not (isinstance(v, (int, float)) and math.isfinite(v)):
            raise ValueError(f"{name} = {v!r} is not allowed: must be a finite number")
    if target_speed is not None and not math.isfinite(target_speed):
        raise ValueError(
            f"target_speed = {target_speed!r} m/s is not allowed: must be finite or None"
        )
