"""Which returns mislead the localiser? Per-detection evidence for the truth over the estimate.

Drives pure pursuit on the env's default task (detections fidelity) and, at every step where
the estimate is more than 0.5 m off, splits AMCL's log-likelihood ratio log L(true pose) -
log L(estimate) into one term per gated detection, labelled by the simulated path it came
from (direct reflector return, room surface of order k, reflector multipath of order k). A
class with a negative mean is evidence for the wrong pose: a return the measurement model
mispredicts. This is how the missing room corners and reflector ghosts were found
(docs/trust.md).

    .venv/bin/python docs/scripts/llr_by_origin.py ipin2023 --episodes 20 --seed 7000
"""

from __future__ import annotations

import argparse
import collections

import gymnasium as gym
import numpy as np

import lrp_gym  # noqa: F401  (registers the envs)
from agents.pure_pursuit import PurePursuitPolicy
from lrp_gym.radar.paths import KIND_NAMES
from lrp_gym.tracking.fingerprint import Fingerprint


def _single(fp: Fingerprint, t: int, k: int) -> Fingerprint:
    """The fingerprint holding only distance k of type t."""
    types = range(len(fp.type_names))
    pick = [np.array([k]) if u == t else np.zeros(0, int) for u in types]
    vel = fp.velocities_mps
    return Fingerprint(
        fp.type_names,
        tuple(fp.distances_m[u][pick[u]] for u in types),
        tuple(fp.variances_m2[u][pick[u]] for u in types),
        tuple(fp.fresh[u][pick[u]] for u in types),
        tuple(vel[u][pick[u]] for u in types) if vel is not None else None,
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", nargs="?", default="ipin2023")
    ap.add_argument("--episodes", type=int, default=20)
    ap.add_argument("--seed", type=int, default=7000)
    ap.add_argument(
        "--set",
        dest="sets",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="localization setting, e.g. ghost_probability=0 (read as a float)",
    )
    args = ap.parse_args()
    loc = {k: float(v) for k, v in (s.split("=", 1) for s in args.sets)}
    env = gym.make(
        "LRPRadarNavFast-v0",
        scenario=args.scenario,
        task_mode="goal",
        overrides={"localization": loc} if loc else None,
    )
    policy = PurePursuitPolicy.from_env(env)
    base = env.unwrapped
    model = base.localizer.model
    lim = base.world.robot
    llr = collections.defaultdict(list)
    for ep in range(args.episodes):
        obs, info = env.reset(seed=args.seed + ep)
        policy.reset()
        done = False
        while not done:
            action = policy.act(obs)
            obs, _, terminated, truncated, info = env.step(action)
            done = terminated or truncated
            if info["position_error_m"] < 0.5:
                continue
            det = base.detections
            fp = base.tracker.gated_fingerprint(det, base.tracker.classifier.candidates(det))
            paths = base.sensor.last_paths
            poses = np.stack([np.asarray(info["true_pose"]), np.asarray(info["est_pose"])])
            speed = action[0] * (lim.max_speed_mps if action[0] >= 0 else lim.max_reverse_mps)
            vel = speed * np.column_stack([np.cos(poses[:, 2]), np.sin(poses[:, 2])])
            for t, dists in enumerate(fp.distances_m):
                for k, z in enumerate(dists):
                    ll = model.log_likelihood(poses, _single(fp, t, k), velocity_xy=vel)
                    j = int(np.argmin(np.abs(paths.range_m - z)))
                    near = abs(paths.range_m[j] - z) <= 0.08
                    label = (
                        f"{KIND_NAMES[paths.kind[j]]} (order {paths.order[j]})"
                        if near
                        else "unexplained"
                    )
                    llr[label].append(ll[0] - ll[1])
    print(f"{'origin':34s} {'n':>5s} {'mean LLR':>9s} {'share < 0':>9s}")
    for label, v in sorted(llr.items(), key=lambda kv: -len(kv[1])):
        v = np.asarray(v)
        print(f"{label:34s} {len(v):5d} {v.mean():+9.2f} {np.mean(v < 0):9.2f}")


if __name__ == "__main__":
    main()
