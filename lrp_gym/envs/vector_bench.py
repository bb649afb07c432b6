"""Steps per second of the batched env against the single env, and where the time goes.

``lrp-gym bench -c vector``: for each radar fidelity, the single env and the vector env with
N robots, on the default task (sampled goals, autoreset included), driven with the same
random action stream, timed after ``WARMUP_STEPS`` steps. Figures are per core (the bench pins itself to one); the ratio
``speedup_vs_single`` is what the batching buys, measured within one run. Each rate is also
given per CPU second of the process (``*_per_cpu_s``, ``speedup_vs_single_cpu``): on a shared
machine the wall-clock rates move with the other processes' load, the CPU rates much less.
"""

from __future__ import annotations

import resource
import time

import gymnasium as gym
import numpy as np

from lrp_gym.config import ScenarioConfig
from lrp_gym.envs.vector_env import LRPRadarNavVectorEnv

BATCH_SIZES = (1, 8, 64, 256)
#: Steps run before timing: the first frames of an episode (global localisation over 10 000
#: particles) cost several times a converged frame, and a batch timed over two steps would
#: measure only them.
WARMUP_STEPS = 10
#: Timed steps at least, whatever ``seconds`` says.
MIN_STEPS = 5
FIDELITIES = ("detections", "signal")
_STAGES = ("radar", "tracking_localization", "lut")


def _actions(rng: np.random.Generator, n: int) -> np.ndarray:
    """Mostly forward, turning a little: episodes end by goal, collision or the step limit."""
    return np.column_stack([rng.uniform(0.2, 0.8, n), rng.uniform(-0.4, 0.4, n)])


def single_env_steps_per_s(cfg: ScenarioConfig, seconds: float) -> tuple[float, float]:
    """Steps per wall second and per CPU second of the single env."""
    env = gym.make("LRPRadarNav-v0", scenario=cfg).unwrapped
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    for _ in range(WARMUP_STEPS):
        env.step(_actions(rng, 1)[0])
    steps, t0, c0 = 0, time.perf_counter(), time.process_time()
    while time.perf_counter() - t0 < seconds or steps < MIN_STEPS:
        _, _, terminated, truncated, _ = env.step(_actions(rng, 1)[0])
        steps += 1
        if terminated or truncated:
            env.reset()
    return steps / (time.perf_counter() - t0), steps / (time.process_time() - c0)


def vector_env_figures(cfg: ScenarioConfig, num_envs: int, seconds: float) -> dict:
    """Steps/s of ``num_envs`` robots (robot-steps per wall second) and the stage split."""
    venv = LRPRadarNavVectorEnv(num_envs, scenario=cfg)
    rng = np.random.default_rng(0)
    venv.reset(seed=0)
    for _ in range(WARMUP_STEPS):
        venv.step(_actions(rng, num_envs))
    stage_s = dict.fromkeys(_STAGES, 0.0)
    steps, t0, c0 = 0, time.perf_counter(), time.process_time()
    while time.perf_counter() - t0 < seconds or steps < MIN_STEPS:
        venv.step(_actions(rng, num_envs))
        steps += 1
        for frame in venv.core.frames:
            if frame is not None:
                for k in _STAGES:
                    stage_s[k] += frame.elapsed_s.get(k, 0.0)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    venv.close()
    split = {f"{k}_share": v / wall for k, v in stage_s.items()}
    split["task_and_glue_share"] = max(0.0, 1.0 - sum(split.values()))
    rates = {"steps_per_s": steps * num_envs / wall, "steps_per_cpu_s": steps * num_envs / cpu}
    return {**rates, "batch_steps": steps, **split}


def bench_vector(cfg: ScenarioConfig, seconds: float, batch_sizes=BATCH_SIZES) -> dict:
    """Single env and vector env (N in ``batch_sizes``) per fidelity, and the peak memory."""
    out: dict = {}
    for fidelity in FIDELITIES:
        fcfg = cfg.with_overrides({"radar": {"fidelity": fidelity}, "task": {"mode": "goal"}})
        single, single_cpu = single_env_steps_per_s(fcfg, seconds)
        rows: dict = {"single_env_steps_per_s": single, "single_env_steps_per_cpu_s": single_cpu}
        for n in batch_sizes:
            fig = vector_env_figures(fcfg, n, seconds)
            fig["speedup_vs_single"] = fig["steps_per_s"] / single
            fig["speedup_vs_single_cpu"] = fig["steps_per_cpu_s"] / single_cpu
            rows[f"N={n}"] = fig
        out[fidelity] = rows
    # ru_maxrss is in kB on Linux: the peak of the whole run, largest batch included.
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return {"vector": {**out, "peak_rss_mb": peak_mb}}
