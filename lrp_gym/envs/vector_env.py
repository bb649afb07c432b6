"""``gym.make_vec("LRPRadarNav-v0", num_envs=N)``: N robots in one :class:`NavBatch`.

The vector entry point of every env id (:mod:`lrp_gym.envs`). The robots share the room, the
map and the radar model; each has its own localisation stack and its own random generator,
seeded ``seed + i`` as Gymnasium's vector envs do, so robot ``i`` follows exactly the
trajectory of ``gym.make(id).reset(seed=seed + i)`` driven with the same actions.

Autoreset is Gymnasium's next-step mode (``metadata["autoreset_mode"]``): the step after robot
``i``'s episode ended ignores its action, starts its next episode and returns that episode's
first observation with reward 0 and neither flag set. ``info`` is Gymnasium's vector dict (one
array per key, and a ``_key`` mask of the robots that have it).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space, concatenate, create_empty_array

from lrp_gym.config import ScenarioConfig
from lrp_gym.envs.nav_batch import NavBatch, RobotView
from lrp_gym.envs.nav_env import build_config


def robot_seeds(seed: int | list[int | None] | None, num_envs: int) -> list[int | None]:
    """Per-robot seeds as Gymnasium's vector envs derive them: ``seed + i``, or a list."""
    if seed is None or isinstance(seed, int | np.integer):
        return [None if seed is None else int(seed) + i for i in range(num_envs)]
    seeds = list(seed)
    if len(seeds) != num_envs:
        raise ValueError(f"seed: expected an int or {num_envs} seeds, got {len(seeds)}")
    return seeds


def check_actions(actions: Any, num_envs: int) -> np.ndarray:
    """Actions as float (N, 2) clipped to [-1, 1] (ValueError naming ``actions``)."""
    a = np.asarray(actions, dtype=float)
    if a.shape != (num_envs, 2):
        raise ValueError(
            f"actions must have shape ({num_envs}, 2) = (robots, (speed, turn)), got {a.shape}"
        )
    if not np.all(np.isfinite(a)):
        raise ValueError("actions must be finite")
    return np.clip(a, -1.0, 1.0)


class LRPRadarNavVectorEnv(VectorEnv):
    """N robots of one scenario stepped together; the arguments are the single env's.

    Parameters
    ----------
    num_envs : int
        Robots in the batch.
    scenario, overrides, radar_fidelity, observation, task_mode
        As :class:`~lrp_gym.envs.nav_env.LRPRadarNavEnv`.
    render_mode : {"rgb_array"}, optional
        ``render()`` draws robot 0.
    max_episode_steps : int, optional
        A step limit on top of the scenario's ``task.max_episode_steps``, as
        ``gym.make(id, max_episode_steps=N)`` adds gymnasium's ``TimeLimit`` to the single env
        (``gym.make_vec`` passes it here): robot ``i`` is truncated after ``N`` steps of its
        episode, with the flags the single env's ``TimeLimit`` gives.
    """

    metadata = {
        "render_modes": ["rgb_array"],
        "render_fps": 4,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self,
        num_envs: int = 1,
        scenario: str | dict | ScenarioConfig | None = None,
        overrides: dict[str, Any] | None = None,
        *,
        radar_fidelity: str | None = None,
        observation: str | None = None,
        task_mode: str | None = None,
        render_mode: str | None = None,
        max_episode_steps: int | None = None,
    ) -> None:
        if max_episode_steps is not None and (
            isinstance(max_episode_steps, bool)
            or not isinstance(max_episode_steps, int | np.integer)
            or max_episode_steps < 1
        ):
            raise ValueError(
                f"max_episode_steps must be a positive int or None, got {max_episode_steps!r}"
            )
        self.max_episode_steps = None if max_episode_steps is None else int(max_episode_steps)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be 'rgb_array' or None, got {render_mode!r}")
        self.cfg = build_config(
            scenario,
            overrides,
            radar_fidelity=radar_fidelity,
            observation=observation,
            task_mode=task_mode,
        )
        self.core = NavBatch(self.cfg, num_envs)
        self.num_envs = self.core.num_robots
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.core.dt_s)}
        self.single_observation_space = self.core.obs_type.space
        self.single_action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._rngs: list[np.random.Generator | None] = [None] * self.num_envs
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._renderer = None

    # ------------------------------------------------------------------ gymnasium API
    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        """Reset every robot (or those of ``options["reset_mask"]``); seeds ``seed + i``."""
        seeds = robot_seeds(seed, self.num_envs)
        # The vector env's own generator (unused by the robots) takes an int seed only.
        super().reset(seed=seed if isinstance(seed, int) else None)
        mask = np.ones(self.num_envs, dtype=bool)
        if options and "reset_mask" in options:
            mask = np.asarray(options["reset_mask"], dtype=bool)
            if mask.shape != (self.num_envs,):
                raise ValueError(f"options['reset_mask'] must have shape ({self.num_envs},)")
            never = [i for i in range(self.num_envs) if self._rngs[i] is None and not mask[i]]
            if never:
                raise ValueError(f"options['reset_mask']: robots {never} were never reset")
        infos: dict[str, Any] = {}
        for i in np.flatnonzero(mask):
            if seeds[i] is not None or self._rngs[i] is None:
                self._rngs[i] = seeding.np_random(seeds[i])[0]
            self.core.reset_robot(int(i), self._rng(int(i)))
            self._autoreset[i] = False
            info = self.core.info(int(i), collided=False, reached=False, reward_terms=None)
            infos = self._add_info(infos, info, int(i))
        return self._observations(), infos

    def step(self, actions):
        """Step every robot; robots whose episode ended at the last step start a new one."""
        actions = check_actions(actions, self.num_envs)
        if any(rng is None for rng in self._rngs):
            raise RuntimeError("call reset() first: the robots have no episode yet")
        rewards = np.zeros(self.num_envs)
        terminated = np.zeros(self.num_envs, dtype=bool)
        truncated = np.zeros(self.num_envs, dtype=bool)
        stepped = np.flatnonzero(~self._autoreset)
        out = self.core.step(actions[stepped], self._rngs, stepped)
        rewards[stepped] = out.reward
        terminated[stepped] = out.terminated
        truncated[stepped] = out.truncated
        if self.max_episode_steps is not None:  # TimeLimit's flag: set even on a termination
            truncated[stepped] |= self.core.steps[stepped] >= self.max_episode_steps
        infos: dict[str, Any] = {}
        for k, i in enumerate(stepped):
            info = self.core.info(
                int(i),
                collided=bool(out.collided[k]),
                reached=bool(out.reached[k]),
                reward_terms=out.reward_terms[k],
            )
            infos = self._add_info(infos, info, int(i))
        for i in np.flatnonzero(self._autoreset):
            self.core.reset_robot(int(i), self._rng(int(i)))
            info = self.core.info(int(i), collided=False, reached=False, reward_terms=None)
            infos = self._add_info(infos, info, int(i))
        self._autoreset = terminated | truncated
        return self._observations(), rewards, terminated, truncated, infos

    def render(self):
        """Robot 0's frame (``render_mode="rgb_array"``)."""
        if self.render_mode is None:
            return None
        if self._rngs[0] is None:
            raise RuntimeError("call reset() first: render() draws the current episode")
        if self._renderer is None:
            from lrp_gym.envs.rendering import Renderer

            self._renderer = Renderer(self.core.world, self.cfg.env.render_size_px, "rgb_array")
        return self._renderer.draw(RobotView(self.core, 0))

    def close_extras(self, **kwargs: Any) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # ------------------------------------------------------------------ internals
    def _rng(self, i: int) -> np.random.Generator:
        rng = self._rngs[i]
        if rng is None:
            raise RuntimeError(f"robot {i} has no generator: reset() first")
        return rng

    def _observations(self):
        items = [self.core.observe(i) for i in range(self.num_envs)]
        # A fresh array per step: a caller may keep the previous observations.
        out = create_empty_array(self.single_observation_space, self.num_envs)
        return concatenate(self.single_observation_space, items, out)
