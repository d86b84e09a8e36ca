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


#: the default target speed [m/s]: the paper's bound, "the resulting average forward speed
#: was approximately 1.3 m/s" (Sec. II, Fig. 5)
DEFAULT_TARGET_SPEED = 1.3


@dataclass(frozen=True)
class Reward:
    """The reward and the termination of :class:`~scoutsim.envs.bound.BoundEnv` (each field
    is also a keyword of the environment, which overrides the bundle's).

    The defaults make running the optimum. Per step of a robot that is up, the forward
    term pays up to ``forward_reward_weight`` x ``target_speed`` (1.3 at the paper's
    1.3 m/s) and the healthy term 0.25: a robot that runs at the target speed earns about
    six times what one that stands still earns, and one that falls loses every step it
    would have earned, so neither standing nor a lunge that falls can pay more than a
    bound. The energy term is the price of the motors' electrical energy: about 0.05 per
    step of Scout II's bound, small next to the forward term, so it shapes how the robot
    runs, not whether.

    Attributes
    ----------
    forward_reward_weight : float
        Weight [1 / (m/s)] of the forward term.
    target_speed : float or None
        v* [m/s]: the forward term is ``forward_reward_weight`` x (v* - |v - v*|), v the
        torso's mean forward speed over the step: v itself up to v*, falling off beyond
        it (it tracks v*, and running twice as fast pays what standing pays); None:
        ``forward_reward_weight`` x v, speed itself without bound. Default 1.3 m/s.
    energy_cost_weight : float
        Price [1/J] of the electrical energy into the motors over the step.
    healthy_reward : float
        Paid at each step that ends with the robot up (default 0.25: a fifth of the
        forward term at the target speed, so it cannot dominate it).
    terminate_when_fallen : bool
        End the episode when the robot is not up.
    healthy_height_range : (min, max) [m]
        COM heights at which the robot is up.
    healthy_pitch_range : (min, max) [rad]
        Pitch at which it is up.
    """

    forward_reward_weight: float = 1.0
    target_speed: float | None = DEFAULT_TARGET_SPEED
    energy_cost_weight: float = 0.01
    healthy_reward: float = 0.25
    terminate_when_fallen: bool = True
    healthy_height_range: tuple = (0.2, math.inf)
    healthy_pitch_range: tuple = (-math.radians(30.0), math.radians(30.0))


def forward_reward(weight: float, v: float, target_speed: float | None) -> float:
    """The forward term of a step at mean forward speed ``v`` [m/s] (:class:`Reward`)."""
    if target_speed is None:
        return weight * v
    return weight * (target_speed - abs(v - target_speed))


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
