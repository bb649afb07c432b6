"""Episodes on fixed seeds, several robots at a time in one :class:`NavBatch`.

Each robot of the batch runs one episode after another from a queue of seeds; an episode
seeded ``s`` draws from ``seeding.np_random(s)`` as ``env.reset(seed=s)`` does, and every robot
drives with its own copy of the policy, so each episode is the one the sequential runner gives
for that seed. A robot whose queue is empty stops (it is not stepped any more).
"""

from __future__ import annotations

import copy
from collections.abc import Callable

import numpy as np
from gymnasium.utils import seeding

from lrp_gym.config import ScenarioConfig
from lrp_gym.envs.nav_batch import NavBatch
from lrp_gym.envs.nav_env import check_action
from lrp_gym.experiments.episodes import EpisodeRecorder, EpisodeResult, Policy, kidnap_frame


def run_batched(
    policy: Policy,
    cfg: ScenarioConfig,
    seeds: list[int],
    num_envs: int,
    progress: Callable[[EpisodeResult], None] | None = None,
) -> list[EpisodeResult]:
    """One episode per seed of ``seeds`` with ``num_envs`` robots at once; results in seed
    order. ``progress`` is called as episodes finish (in finishing order)."""
    n = min(num_envs, len(seeds))
    batch = NavBatch(cfg, n)
    policies = [copy.deepcopy(policy) for _ in range(n)]
    rngs: list[np.random.Generator] = [seeding.np_random(0)[0]] * n
    recorders: list[EpisodeRecorder | None] = [None] * n
    obs: list = [None] * n
    queue = list(seeds)
    done: dict[int, EpisodeResult] = {}
    dt_s = float(cfg.task.frame_period_s)

    def start(j: int) -> None:
        s = queue.pop(0)
        rngs[j] = seeding.np_random(s)[0]
        batch.reset_robot(j, rngs[j])
        policies[j].reset()
        info = batch.info(j, collided=False, reached=False, reward_terms=None)
        recorders[j] = EpisodeRecorder(s, info, batch.path(j).waypoints_m, dt_s)
        obs[j] = batch.observe(j)

    for j in range(n):
        start(j)
    while any(r is not None for r in recorders):
        robots = np.array([j for j in range(n) if recorders[j] is not None], dtype=np.intp)
        actions = np.stack([check_action(policies[j].act(obs[j])) for j in robots])
        out = batch.step(actions, rngs, robots)
        for k, j in enumerate(robots):
            info = batch.info(
                int(j),
                collided=bool(out.collided[k]),
                reached=bool(out.reached[k]),
                reward_terms=out.reward_terms[k],
            )
            record = recorders[j]
            assert record is not None
            record.add(float(out.reward[k]), info)
            obs[j] = batch.observe(int(j))
            if out.terminated[k] or out.truncated[k]:
                done[record.seed] = record.result(kidnap_frame(batch.perturbations[j]))
                if progress is not None:
                    progress(done[record.seed])
                recorders[j] = None
                if queue:
                    start(int(j))
    return [done[s] for s in seeds]
