"""Do the radar's misses of a reflector in view repeat from frame to frame?

Pure pursuit on the env's default task (detections fidelity), optionally in the paper room
with the obstacle-room box and with unmapped clutter: over the reflectors in view of the true
position, the share of frames whose fingerprint holds no distance within 0.15 m of the
reflector's (a miss), the same share among frames that follow a miss of that reflector, and
the share of chance matches (a distance within 0.15 m of the reflector's plus 0.37 m).

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/miss_persistence.py SEVERITY FIRST_SEED \
        END_SEED OBSTACLE   # e.g. 0.5 7300 7360 1
"""

import sys

import gymnasium as gym
import numpy as np

import lrp_gym  # noqa: F401  (registers the ids)
from agents.pure_pursuit import PurePursuitPolicy
from lrp_gym.world.reflector_view import reflector_view

BOX = {"min": [0.8, 1.4, 0.0], "max": [2.2, 2.6, 1.0]}
TOLERANCE_M = 0.15


def main() -> None:
    severity = float(sys.argv[1])
    seeds = range(int(sys.argv[2]), int(sys.argv[3]))
    over: dict = {"room": {"obstacles": [BOX]}} if sys.argv[4] == "1" else {}
    if severity > 0.0:
        over["perturbations"] = {"clutter": {"severity": severity}}
    env = gym.make("LRPRadarNavFast-v0", task_mode="goal", overrides=over)
    policy = PurePursuitPolicy.from_env(env)
    core = env.unwrapped.core
    world = core.world
    frames = misses = after_miss = misses_after_miss = chance = 0
    for seed in seeds:
        policy.reset()
        obs, info = env.reset(seed=seed)
        done, last = False, None
        while not done:
            obs, _, terminated, truncated, info = env.step(policy.act(obs))
            done = terminated or truncated
            xy = np.asarray(info["true_pose"])[:2]
            fp = core.frames[0].fingerprint
            z = np.concatenate([np.asarray(d) for d in fp.distances_m]) if fp else np.zeros(0)
            room, lay, h, r_max = (
                world.room,
                world.layout,
                world.mount_height_m,
                world.fmcw.max_range_m,
            )
            in_view = reflector_view(room, lay, h, r_max, xy[None]).in_view[:, 0]
            d = world.true_distances_m(xy)
            missed = np.array([not np.any(np.abs(z - dj) < TOLERANCE_M) for dj in d])
            chance += sum(np.any(np.abs(z - dj - 0.37) < TOLERANCE_M) for dj in d[in_view])
            for j in np.flatnonzero(in_view):
                frames += 1
                misses += missed[j]
                if last is not None and last[0][j] and last[1][j]:
                    after_miss += 1
                    misses_after_miss += missed[j]
            last = (in_view, missed)
    print(
        f"P(miss) {misses / frames:.3f} of {frames} reflector-frames in view, "
        f"P(miss | missed the frame before) {misses_after_miss / max(after_miss, 1):.3f} "
        f"of {after_miss}, chance match {chance / frames:.3f}"
    )


if __name__ == "__main__":
    main()
