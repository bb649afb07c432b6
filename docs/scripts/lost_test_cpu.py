"""CPU time per env step with the lost test every frame or every k-th quiet frame.

300 seeded random-action steps after 10 warm-up steps, default task, `time.process_time`
(robust to other processes' load):

    python docs/scripts/lost_test_cpu.py LRPRadarNavFast-v0 1 4 1 4
"""

from __future__ import annotations

import sys
import time

import gymnasium as gym
import numpy as np

import lrp_gym.envs  # noqa: F401  (registers the env ids)


def cpu_ms_per_step(env_id: str, every: int, steps: int = 300) -> float:
    env = gym.make(env_id, overrides={"localization": {"lost_test_every": every}})
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    for _ in range(10):
        env.step(rng.uniform(-1, 1, 2).astype(np.float32))
    t0 = time.process_time()
    for _ in range(steps):
        *_, term, trunc, _ = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        if term or trunc:
            env.reset()
    return 1000.0 * (time.process_time() - t0) / steps


if __name__ == "__main__":
    env_id = sys.argv[1]
    for k in map(int, sys.argv[2:] or ["1", "4"]):
        print(f"{env_id} lost_test_every={k}: {cpu_ms_per_step(env_id, k):.2f} CPU ms/step")
