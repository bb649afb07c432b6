"""Why seed 7380 sticks under clutter (docs/trust.md, session 25): the estimate against the goal.

Pure pursuit on the default task with unmapped clutter 0.5 and ``converged_mass`` 0.99, seed
7380: every second step from step 18, the action, the estimated and true pose and their
distances to the goal. The wrong estimate reaches the goal; pure pursuit then turns on the
spot, so no frame brings new evidence and the episode runs out its 200 steps.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/stuck_at_goal_trace.py
"""

import gymnasium as gym, numpy as np
import lrp_gym  # noqa
from agents.pure_pursuit import PurePursuitPolicy
over = {"perturbations": {"clutter": {"severity": 0.5}}, "localization": {"converged_mass": 0.99}}
env = gym.make("LRPRadarNavFast-v0", task_mode="goal", overrides=over)
policy = PurePursuitPolicy.from_env(env); base = env.unwrapped
policy.reset(); obs, info = env.reset(seed=7380); done = False; k = 0
goal = np.asarray(base.path.waypoints_m[-1])
print("goal", goal)
while not done and k < 40:
    a = policy.act(obs)
    obs, _, t, tr, info = env.step(a); done = t or tr; k += 1
    if k >= 18 and k % 2 == 0:
        est = np.asarray(info["est_pose"]); tru = np.asarray(info["true_pose"])
        print(k, "action", np.round(a, 2), "est", np.round(est, 2), "true", np.round(tru, 2), "est->goal %.2f" % np.linalg.norm(est[:2]-goal), "true->goal %.2f" % np.linalg.norm(tru[:2]-goal))
