"""Converged but wrong: does the measurement model prefer the truth or the wrong estimate?

Drives sampled-goal episodes (pure pursuit, detections fidelity) with a clutter perturbation
and, on every frame where the estimate has converged more than 0.3 m from the truth, compares
the log-likelihood of the frame's gated detections at the true position and at the estimate.
Negative: the model itself prefers the wrong pose (physically ambiguous per frame); positive
but small: the truth is better by less than the lost test needs to notice.

    python docs/scripts/wrong_mode_likelihood.py ipin2023 0.5 7000 12
"""

from __future__ import annotations

import sys

import gymnasium as gym
import numpy as np

import lrp_gym.envs  # noqa: F401  (registers the env ids)
from agents.pure_pursuit import PurePursuitPolicy


def main(scenario: str, severity: float, first_seed: int, episodes: int) -> None:
    overrides = {"perturbations": {"clutter": {"severity": severity}}, "task": {"mode": "goal"}}
    env = gym.make("LRPRadarNavFast-v0", scenario=scenario, overrides=overrides)
    base = env.unwrapped
    policy = PurePursuitPolicy.from_env(env)
    for seed in range(first_seed, first_seed + episodes):
        policy.reset()
        obs, _ = env.reset(seed=seed)
        model = base.localizer.model
        gaps, wrong, frames = [], 0, 0
        for _ in range(base.cfg.task.max_episode_steps):
            obs, _, term, trunc, info = env.step(policy.act(obs))
            frames += 1
            wrong += info["position_error_m"] > 0.3
            fp = base.tracker.gated_fingerprint()
            if fp.count and base.estimate.converged and info["position_error_m"] > 0.3:
                at_truth = model.log_likelihood(base.pose[None, :2].copy(), fp)[0]
                at_estimate = model.log_likelihood(base.estimate.pose[None, :2].copy(), fp)[0]
                gaps.append(float(at_truth - at_estimate))
            if term or trunc:
                break
        g = np.array(gaps)
        mean = f"{g.mean():+.2f}" if len(g) else "-"
        print(
            f"seed {seed}: {frames} frames, {wrong} off by > 0.3 m, {len(g)} of them converged;"
            f" log L(truth) - log L(estimate) per frame {mean}"
        )


if __name__ == "__main__":
    a = sys.argv[1:]
    main(
        a[0] if a else "ipin2023",
        float(a[1]) if len(a) > 1 else 0.5,
        int(a[2]) if len(a) > 2 else 7000,
        int(a[3]) if len(a) > 3 else 12,
    )
