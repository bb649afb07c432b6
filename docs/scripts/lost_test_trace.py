"""One default-task episode step by step: the lost test beside the confidence (docs/trust.md,
session 19: frames at the same spot fed the lost test).

Pure pursuit on the default task with unmapped scatterers; per step the action, the position
error, the confidence, the converged flag, the particle count, and the lost test's two
statistics (``statistic_nats``, ``alternative_nats``) and this frame's deficit.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/lost_test_trace.py --seed 7008 \
        [--severity 0.5] [--avoid-walls]
"""

from __future__ import annotations

import argparse

import gymnasium as gym

import lrp_gym  # noqa: F401  (registers the ids)
from agents.pure_pursuit import PurePursuitPolicy


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=7008)
    ap.add_argument("--severity", type=float, default=0.5, help="clutter severity (0: none)")
    ap.add_argument("--avoid-walls", action="store_true", help="avoid_walls_when_unsure on")
    args = ap.parse_args()
    over = {"perturbations": {"clutter": {"severity": args.severity}}} if args.severity else {}
    env = gym.make("LRPRadarNavFast-v0", task_mode="goal", overrides=over)
    policy = PurePursuitPolicy.from_env(env, avoid_walls_when_unsure=args.avoid_walls)
    lost = env.unwrapped.core.stacks[0].localizer.lost
    obs, _ = env.reset(seed=args.seed)
    print("step | action | error m | confidence | converged | particles | stat | alt | deficit")
    step, done = 0, False
    while not done:
        action = policy.act(obs)
        obs, _, terminated, truncated, info = env.step(action)
        done, step = terminated or truncated, step + 1
        print(
            f"{step} | {action[0]:+.2f} {action[1]:+.2f} | {info['position_error_m']:.2f} | "
            f"{info['localization_confidence']:.3f} | {int(info['converged'])} | "
            f"{info['n_particles']} | {lost.statistic_nats:.1f} | {lost.alternative_nats:.1f} | "
            f"{lost.last_deficit_nats:.1f}"
        )
    env.close()


if __name__ == "__main__":
    main()
