"""Why the reflector monitor names an unmoved reflector under clutter: the radar misses it.

One patrol episode (2 + 2 layout, pure pursuit, detections fidelity). On every converged
frame: is reflector J's direct return among the detections (within 0.1 m of its true
distance)? And would a veto "a return above 6 dBsm within the CFAR window (10 range cells,
4 Doppler cells) of the reflector's true range and radial velocity" tell those frames apart?

    python docs/scripts/monitor_masking.py SEED J SEVERITY     # e.g. 0 1 0.5, then 0 1 0
"""

from __future__ import annotations

import sys

import numpy as np

from agents.registry import make_agent
from lrp_gym.experiments.episodes import make_eval_env
from lrp_gym.experiments.robustness import cell_overrides


def main(seed: int, j: int, severity: float) -> None:
    overrides = cell_overrides("clutter", severity) or None
    env = make_eval_env(
        "pure-pursuit", "LRPRadarNavFast-v0", "ipin2023-2types-patrol", overrides=overrides
    )
    policy = make_agent("pure-pursuit", env)
    policy.reset()
    obs, _ = env.reset(seed=seed)
    base = env.unwrapped
    world, fm = base.world, base.world.fmcw
    prev = base.pose.copy()
    frames = missing = vetoed = vetoed_missing = 0
    for _ in range(base.cfg.task.max_episode_steps):
        obs, _, term, trunc, _ = env.step(policy.act(obs))
        pose, det = base.pose, base.detections
        velocity = (pose[:2] - prev[:2]) / base.dt_s
        prev = pose.copy()
        if base.estimate.converged and det is not None and len(det):
            radar = world.radar_position(pose[:2])
            q = world.layout.positions_m[j]
            d = float(np.linalg.norm(q - radar))
            vr = float(-(velocity @ (q[:2] - radar[:2])) / d)
            have = bool(np.min(np.abs(det.range_m - d)) < 0.1)
            near = (
                (np.abs(det.range_m - d) <= 10 * fm.range_resolution_m)
                & (np.abs(det.velocity_mps - vr) <= 4 * fm.velocity_resolution_mps)
                & (det.rcs_dbsm > 6.0)
                & (np.abs(det.range_m - d) > 0.1)
            )
            frames += 1
            missing += not have
            vetoed += bool(near.any())
            vetoed_missing += bool(near.any()) and not have
        if term or trunc:
            break
    print(
        f"converged frames {frames}: reflector {j} missing in {missing} "
        f"({100 * missing / max(frames, 1):.1f} %); veto fires in {vetoed} "
        f"({100 * vetoed / max(frames, 1):.0f} %), {vetoed_missing} of them missing"
    )


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3]))
