"""Converged-but-wrong steps in a room with an obstacle, by how many reflectors it hides.

Pure pursuit on the env's default task in the paper room with a 1.4 m x 1.2 m x 1 m box
(the obstacle-room rows of docs/trust.md), with or without unmapped clutter: the converged
steps and the wrong ones (> 0.3 m off), split by how many reflectors the box hides from the
true position and from the estimate; and the env steps per CPU second.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/obstacle_room_visibility.py --seeds 7300-7399 \\
        [--severity 0.5] [--set localization.detection_probability=0.6]
"""

from __future__ import annotations

import time
from collections import Counter

import numpy as np
from wrong_converged_features import default_task_steps, study_args  # the script beside this one

from lrp_gym.localization.metrics import CONFIDENTLY_WRONG_M

BOX_SET = "room.obstacles=[{min: [0.8, 1.4, 0.0], max: [2.2, 2.6, 1.0]}]"


def hidden_count(world, xy: np.ndarray) -> int:
    """How many reflectors the room's obstacles hide from a radar at floor position ``xy``."""
    pos = world.layout.positions_m
    radar = np.broadcast_to(world.radar_position(np.asarray(xy, float)), pos.shape)
    return int(world.room.segments_blocked(radar, pos).sum())


def main() -> None:
    args = study_args(__doc__, sets=(BOX_SET,))
    steps, wrong = Counter(), Counter()
    n_steps, cpu_s = 0, time.process_time()
    for step, info, amcl in default_task_steps(args.seeds, args.severity, args.overrides):
        n_steps += step > 0
        if step == 0 or not info["converged"]:
            continue
        world = amcl.world
        truth = hidden_count(world, np.asarray(info["true_pose"])[:2])
        est = hidden_count(world, np.asarray(info["est_pose"])[:2])
        steps[truth] += 1
        if info["position_error_m"] > CONFIDENTLY_WRONG_M:
            wrong[(truth, est)] += 1
    cpu_s = time.process_time() - cpu_s  # the counting below is not timed
    total, bad = sum(steps.values()), sum(wrong.values())
    print(f"{total} converged steps, {bad} wrong (> {CONFIDENTLY_WRONG_M} m): {bad / total:.1%}")
    print("reflectors hidden at the truth | converged steps | wrong")
    for k in sorted(steps):
        n_wrong = sum(v for (t, _), v in wrong.items() if t == k)
        print(f"{k} | {steps[k]} | {n_wrong}")
    print("wrong steps by reflectors hidden at the truth / at the estimate:")
    print(", ".join(f"{t}/{e}: {v}" for (t, e), v in sorted(wrong.items())))
    print(f"{n_steps} env steps, {n_steps / cpu_s:.1f} per CPU second (episodes included)")


if __name__ == "__main__":
    main()
