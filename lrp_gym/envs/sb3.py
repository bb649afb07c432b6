"""Stable-Baselines3's ``VecEnv`` over one :class:`~lrp_gym.envs.nav_batch.NavBatch`.

PPO's ``n_envs`` robots run in one batch in this process instead of ``n_envs`` env copies.
Stable-Baselines3 resets an ended episode in the same step and keeps its last observation in
``info["terminal_observation"]`` (``info["TimeLimit.truncated"]`` tells a truncation), unlike
Gymnasium's next-step autoreset of :mod:`lrp_gym.envs.vector_env`; the random streams are the
same: robot ``i`` seeded ``seed + i`` follows the single env reset with that seed.

Needs the ``rl`` extra (``pip install lrp-gym[rl]``). Wrap it in ``VecMonitor`` for episode
statistics and in ``VecNormalize`` as for any VecEnv.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices

from lrp_gym.envs.nav_batch import NavBatch, RobotView
from lrp_gym.envs.nav_env import build_config
from lrp_gym.envs.vector_env import check_actions


class NavBatchVecEnv(VecEnv):
    """``num_envs`` robots of env id ``env_id`` (its registered kwargs, then ``env_kwargs``).

    Parameters
    ----------
    env_id : str
        A registered LRP env id (``LRPRadarNavFast-v0``, ``lrp_gym:LRPRadarNav-v0``, ...).
    num_envs : int
        Robots in the batch.
    env_kwargs : dict, optional
        The env's keyword arguments (``scenario``, ``overrides``, ...).
    """

    def __init__(self, env_id: str, num_envs: int, env_kwargs: dict[str, Any] | None = None):
        # "lrp_gym:LRPRadarNav-v0" as gym.make takes it: the module is this package.
        kwargs = {**gym.spec(env_id.split(":")[-1]).kwargs, **(env_kwargs or {})}
        if kwargs.pop("render_mode", None) is not None:
            raise ValueError("env_kwargs: render_mode is not supported by the batched VecEnv")
        self.core = NavBatch(build_config(**kwargs), num_envs)
        self.render_mode = None
        self._rngs: list[np.random.Generator | None] = [None] * num_envs
        self._actions = np.zeros((num_envs, 2))
        action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        super().__init__(num_envs, self.core.obs_type.space, action_space)

    def reset(self):
        for i in range(self.num_envs):
            seed = self._seeds[i]
            if seed is not None or self._rngs[i] is None:
                self._rngs[i] = seeding.np_random(seed)[0]
            self._reset_robot(i)
        # Seeds and options are used once, as in SB3's own VecEnvs.
        self._reset_seeds()
        self._reset_options()
        return self._observations()

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = check_actions(actions, self.num_envs)

    def step_wait(self):
        robots = np.arange(self.num_envs)
        out = self.core.step(self._actions, self._rngs, robots)
        dones = out.terminated | out.truncated
        infos = []
        for i in robots:
            info = self.core.info(
                int(i),
                collided=bool(out.collided[i]),
                reached=bool(out.reached[i]),
                reward_terms=out.reward_terms[i],
            )
            info["TimeLimit.truncated"] = bool(out.truncated[i] and not out.terminated[i])
            if dones[i]:
                info["terminal_observation"] = self.core.observe(int(i))
                self._reset_robot(int(i))
            infos.append(info)
        return self._observations(), out.reward.astype(np.float32), dones, infos

    def close(self) -> None:
        pass

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [None] * self.num_envs

    # ------------------------------------------------------------------ attribute access
    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        if attr_name == "render_mode":
            return [None for _ in self._get_indices(indices)]
        return [getattr(RobotView(self.core, i), attr_name) for i in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        raise AttributeError(f"set_attr: the batched env's robots have no settable {attr_name!r}")

    def env_method(self, method_name: str, *args, indices: VecEnvIndices = None, **kwargs):
        views = [RobotView(self.core, i) for i in self._get_indices(indices)]
        return [getattr(v, method_name)(*args, **kwargs) for v in views]

    def env_is_wrapped(self, wrapper_class: type, indices: VecEnvIndices = None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    # ------------------------------------------------------------------ internals
    def _reset_robot(self, i: int) -> None:
        rng = self._rngs[i]
        if rng is None:
            raise RuntimeError("call reset() first")
        self.core.reset_robot(i, rng)
        self.reset_infos[i] = self.core.info(i, collided=False, reached=False, reward_terms=None)

    def _observations(self) -> Any:
        items = [self.core.observe(i) for i in range(self.num_envs)]
        if isinstance(self.observation_space, spaces.Dict):
            return {k: np.stack([o[k] for o in items]) for k in self.observation_space.spaces}
        return np.stack(items)
