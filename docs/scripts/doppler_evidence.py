"""Does the Doppler term point at the truth? Evidence of each frame, distance part and Doppler part.

Drives pure pursuit on the env's default task (detections fidelity) and, on every frame,
evaluates AMCL's measurement model on the frame it weighed at the true pose and at the
estimate, with the particles' velocities (distance and Doppler) and without (distance only).
The difference of the two log-likelihood ratios is the Doppler part. Episodes are grouped by
how many converged steps were more than 0.3 m off; for the frames up to the first converged
one (where a wrong mode is chosen) the distance and Doppler parts are summed. On the
converged wrong frames the Doppler part is split per gated detection (leave-one-out), labelled
by the simulated path it came from.

    python docs/scripts/doppler_evidence.py --episodes 100 \
        --set "room.obstacles=[{min: [0.8, 1.4, 0], max: [2.2, 2.6, 1.0]}]" \
        --set perturbations.clutter.severity=0.5
"""

from __future__ import annotations

import argparse
import collections

import numpy as np

from agents.registry import make_agent
from lrp_gym.commands._common import overrides
from lrp_gym.config import deep_merge
from lrp_gym.experiments.episodes import make_eval_env
from lrp_gym.localization.particle_motion import particle_velocities
from lrp_gym.radar.paths import KIND_NAMES
from lrp_gym.tracking.fingerprint import Fingerprint


def _without(fp: Fingerprint, t: int, k: int) -> Fingerprint:
    """The fingerprint without distance k of type t."""
    keep = [
        np.delete(np.arange(len(d)), k) if u == t else np.arange(len(d))
        for u, d in enumerate(fp.distances_m)
    ]
    vel = fp.velocities_mps
    return Fingerprint(
        fp.type_names,
        tuple(d[i] for d, i in zip(fp.distances_m, keep, strict=True)),
        tuple(d[i] for d, i in zip(fp.variances_m2, keep, strict=True)),
        tuple(d[i] for d, i in zip(fp.fresh, keep, strict=True)),
        tuple(d[i] for d, i in zip(vel, keep, strict=True)) if vel is not None else None,
    )


def _ratios(model, poses, fp, speed) -> tuple[float, float]:
    """log L(truth) - log L(estimate) with the Doppler term and without it."""
    xy = poses[:, :2].copy()
    with_v = model.log_likelihood(xy, fp, velocity_xy=particle_velocities(poses, speed))
    without = model.log_likelihood(xy, fp)
    return float(with_v[0] - with_v[1]), float(without[0] - without[1])


def _origin(paths, z: float, v: float) -> str:
    """The simulated path nearest in range and velocity (within 8 cm), else 'unexplained'."""
    if len(paths.range_m) == 0:
        return "unexplained"
    j = int(np.argmin(np.abs(paths.range_m - z) / 0.05 + np.abs(paths.velocity_mps - v) / 0.3))
    if abs(paths.range_m[j] - z) > 0.08:
        return "unexplained"
    return f"{KIND_NAMES[paths.kind[j]]} (order {paths.order[j]})"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", nargs="?", default="ipin2023")
    ap.add_argument("--episodes", type=int, default=30)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE")
    args = ap.parse_args()
    over = deep_merge(overrides(args.scenario, args.sets), {"task": {"mode": "goal"}})
    env = make_eval_env("pure-pursuit", "LRPRadarNavFast-v0", args.scenario, overrides=over)
    policy = make_agent("pure-pursuit", env)
    base = env.unwrapped
    loc = base.localizer
    seen: dict = {}
    update = loc.update

    def spy(odometry, fingerprint, rng, **kw):
        seen["fp"], seen["speed"] = fingerprint, kw.get("speed_mps")
        return update(odometry, fingerprint, rng, **kw)

    loc.update = spy
    groups = collections.defaultdict(list)
    per_origin = collections.defaultdict(list)
    for seed in range(args.seed, args.seed + args.episodes):
        obs, _ = env.reset(seed=seed)
        policy.reset()
        wrong, before, decided, done = 0, np.zeros(2), False, False
        while not done:
            seen.clear()
            obs, _, term, trunc, info = env.step(policy.act(obs))
            done = term or trunc
            fp = seen.get("fp")
            if fp is None or fp.count == 0:
                continue
            est = base.estimate
            off = info["position_error_m"] > 0.3
            poses = np.stack([np.asarray(info["true_pose"], float), np.asarray(est.pose, float)])
            both, dist = _ratios(loc.model, poses, fp, seen["speed"])
            if not decided and off:
                before += (dist, both - dist)
            decided = decided or est.converged
            if not (est.converged and off):
                continue
            wrong += 1
            for t, dists in enumerate(fp.distances_m):
                for k, z in enumerate(dists):
                    sub = _without(fp, t, k)
                    b2, d2 = _ratios(loc.model, poses, sub, seen["speed"]) if sub.count else (0, 0)
                    v = float(fp.velocities_mps[t][k]) if fp.velocities_mps else np.nan
                    label = _origin(base.sensor.last_paths, float(z), v)
                    per_origin[label].append((both - dist) - (b2 - d2))
        key = "never wrong" if wrong == 0 else ("1-4 wrong" if wrong < 5 else ">= 5 wrong")
        groups[key].append(before)
    print("frames up to the first converged one, summed (truth - estimate, nats):")
    for key in ("never wrong", "1-4 wrong", ">= 5 wrong"):
        if groups[key]:
            g = np.mean(groups[key], axis=0)
            print(
                f"  {key:12s} {len(groups[key]):4d} episodes: distance {g[0]:+6.2f}, Doppler {g[1]:+6.2f}"
            )
    print("converged wrong frames, Doppler part per detection (truth - estimate, nats):")
    for label, v in sorted(per_origin.items(), key=lambda kv: -len(kv[1])):
        print(f"  {label:30s} {len(v):5d} {np.mean(v):+6.2f}")


if __name__ == "__main__":
    main()
