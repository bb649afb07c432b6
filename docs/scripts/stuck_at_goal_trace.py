"""Why seed 7380 sticks under clutter (docs/trust.md, session 25): the estimate against the goal.

Pure pursuit on the default task with unmapped clutter 0.5 and ``converged_mass`` 0.99, seed
7380: every second step from step 18, the action, the estimated and true pose and their
distances to the goal. The wrong estimate reaches the goal; pure pursuit then turns on the
spot, so no frame brings new evidence and the episode runs out its 200 steps.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/stuck_at_goal_trace.py
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

import lrp_gym  # noqa: F401  (registers the ids)
from agents.pure_pursuit import PurePursuitPolicy

OVERRIDES = {
    "perturbations": {"clutter": {"severity": 0.5}},
    "localization": {"converged_mass": 0.99},
}


def main(seed: int = 7380, steps: int = 40) -> None:
    env = gym.make("LRPRadarNavFast-v0", task_mode="goal", overrides=OVERRIDES)
    policy = PurePursuitPolicy.from_env(env)
    policy.reset()
    obs, info = env.reset(seed=seed)
    goal = np.asarray(env.unwrapped.path.waypoints_m[-1])
    print("goal", np.round(goal, 2))
    for k in range(1, steps + 1):
        action = policy.act(obs)
        obs, _, terminated, truncated, info = env.step(action)
        est, true = np.asarray(info["est_pose"]), np.asarray(info["true_pose"])
        if k >= 18 and k % 2 == 0:
            print(
                f"{k}: action {np.round(action, 2)}, estimate {np.round(est, 2)}, "
                f"truth {np.round(true, 2)}, estimate to goal "
                f"{np.linalg.norm(est[:2] - goal):.2f} m, truth to goal "
                f"{np.linalg.norm(true[:2] - goal):.2f} m"
            )
        if terminated or truncated:
            break
    env.close()


if __name__ == "__main__":
    main()
