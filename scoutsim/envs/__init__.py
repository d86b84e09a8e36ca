"""Learning environments (Gymnasium) on the compiled Scout II model.

``import scoutsim.envs`` registers ``scoutsim/Bound-v0`` (:class:`BoundEnv`)::

    import gymnasium, scoutsim.envs
    env = gymnasium.make("scoutsim/Bound-v0", model="II", action_type="setpoints")
    envs = gymnasium.make_vec("scoutsim/Bound-v0", num_envs=4, vectorization_mode="async")
    env = gymnasium.make("scoutsim/Bound-v0", render_mode="rgb_array")   # env.render(): a frame
    env = gymnasium.make("scoutsim/Bound-v0", action_type="setpoints",
                         controller="my_gaits:make")   # Table I parameters of one's own

Needs Gymnasium (``pip install "scoutsim[rl]"``); ``import scoutsim`` alone does not import
it.
"""

from __future__ import annotations

try:
    import gymnasium
except ImportError as exc:  # pragma: no cover - exercised with gymnasium hidden
    raise ImportError(
        "scoutsim.envs needs Gymnasium: pip install 'scoutsim[rl]' "
        "(or pip install 'gymnasium>=1.0')"
    ) from exc

from .bound import BoundEnv

__all__ = ["BoundEnv", "BOUND_ID", "DEFAULT_MAX_EPISODE_STEPS"]

#: the registered id of :class:`BoundEnv`
BOUND_ID = "scoutsim/Bound-v0"
#: the time limit of a registered episode in policy steps (10 s at the default 10 ms
#: policy period; ``gymnasium.make(..., max_episode_steps=n)`` for another)
DEFAULT_MAX_EPISODE_STEPS = 1000

if BOUND_ID not in gymnasium.registry:
    gymnasium.register(
        id=BOUND_ID,
        entry_point="scoutsim.envs.bound:BoundEnv",
        max_episode_steps=DEFAULT_MAX_EPISODE_STEPS,
    )
