"""Steps per second of the registered environment variants."""

from __future__ import annotations

import time

import gymnasium as gym
import numpy as np
from gymnasium.utils.performance import benchmark_step

from lrp_gym.config import ScenarioConfig
from lrp_gym.envs import ENV_VARIANTS

# Slow forward motion while turning: the robot circles on the spot, never collides, and AMCL
# stays converged, which is the steady state the speed targets refer to.
_CIRCLE_ACTION = np.array([0.1, 0.5], dtype=np.float32)


def converged_steps_per_s(
    env: gym.Env, seconds: float, warmup_steps: int = 30, seed: int = 0
) -> float:
    """Steps per second after localisation has converged (resets excluded from the timing)."""
    env.reset(seed=seed)
    _warm_up(env, warmup_steps)
    steps, elapsed = 0, 0.0
    while elapsed < seconds:
        t0 = time.perf_counter()
        for _ in range(50):
            _, _, terminated, truncated, _ = env.step(_CIRCLE_ACTION)
            steps += 1
            if terminated or truncated:
                break
        elapsed += time.perf_counter() - t0
        if terminated or truncated:
            env.reset()
            _warm_up(env, warmup_steps)
    return steps / elapsed


def _warm_up(env: gym.Env, steps: int) -> None:
    """``steps`` untimed circling steps, with a reset wherever an episode ends (in a small
    room the circle may reach a wall; stepping an ended episode is an error)."""
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(_CIRCLE_ACTION)
        if terminated or truncated:
            env.reset()


def bench_envs(cfg: ScenarioConfig, seconds: float) -> dict:
    """Steps/s per variant: converged (paper path start, circling) and gymnasium's random-action
    benchmark (``benchmark_step``, includes resets with a fresh 10000-particle AMCL)."""
    path_task = {"task": {"mode": "path"}}
    out: dict = {}
    for env_id in ENV_VARIANTS:
        env = gym.make(env_id, scenario=cfg, overrides=path_task).unwrapped
        converged = converged_steps_per_s(env, seconds)
        info = env.step(_CIRCLE_ACTION)[4]
        env.close()
        rand_env = gym.make(env_id, scenario=cfg)
        # gymnasium annotates target_duration as int; a float works.
        duration = max(seconds, 1.0)
        with_resets = benchmark_step(rand_env, target_duration=duration, seed=0)  # type: ignore[arg-type]
        rand_env.close()
        out[env_id] = {
            "steps_per_s": converged,
            "steps_per_s_random_actions": with_resets,
            "converged_particles": info["n_particles"],
        }
    # All three counts: a scenario that starts with fewer particles (a valid choice) would
    # otherwise fail validation here, reported as an invalid user scenario.
    n = {"initial_particles": 10000, "min_particles": 10000, "max_particles": 10000}
    fixed = {**path_task, "localization": n}
    env = gym.make("LRPRadarNav-v0", scenario=cfg, overrides=fixed).unwrapped
    out["LRPRadarNav-v0 (fixed 10000 particles)"] = {
        "steps_per_s": converged_steps_per_s(env, seconds)
    }
    env.close()
    return {"variants": out}
