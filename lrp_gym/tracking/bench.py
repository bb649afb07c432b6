"""Speed of the tracker per frame on synthetic streams (``lrp-gym bench`` style entry point)."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from lrp_gym.config import ScenarioConfig
from lrp_gym.tracking.prior import DistancePrior
from lrp_gym.tracking.range_prediction import EgoMotion
from lrp_gym.tracking.synthetic import synthetic_stream
from lrp_gym.tracking.tracker import LrpTracker
from lrp_gym.world.robot import odometry_delta
from lrp_gym.world.trajectory import path_trajectory
from lrp_gym.world.world import World

LOOP_FRACTIONS = [[0.15, 0.15], [0.85, 0.15], [0.85, 0.85], [0.15, 0.85], [0.15, 0.25]]


def bench_tracking(cfg: ScenarioConfig, seconds: float) -> dict:
    """Mean time per :meth:`LrpTracker.update` in microseconds, clean and with clutter.

    The robot loops around the room at 1 m/s with 0.1 s frames; "clean" has every reflector
    detected and no clutter, "clutter" misses 20 % of them and adds 2 reflector-like clutter
    detections per frame on average; "clutter_map_aided" is the same frames with the robot's
    odometry and a distance prior (true pose, 5 cm standard deviation), as in the env.
    """
    world = World.from_config(cfg)
    path = np.asarray(LOOP_FRACTIONS) * world.room.size_m[:2]
    traj = path_trajectory(path, 1.0, 0.1)
    out = {}
    poses = traj.poses
    ego = [EgoMotion(1.0, np.zeros(3))] + [
        EgoMotion(1.0, odometry_delta(poses[k - 1], poses[k])) for k in range(1, len(traj))
    ]
    cov = np.eye(2) * 0.05**2
    priors = [
        DistancePrior.from_pose(world.layout, world.mount_height_m, xy, cov) for xy in poses[:, :2]
    ]
    no_aid = [None] * len(traj)
    cases: dict[str, tuple[dict[str, Any], list[Any], list[Any]]] = {
        "clean": (dict(miss_probability=0.0, clutter_per_frame=0.0), no_aid, no_aid),
        "clutter": ({}, no_aid, no_aid),
        "clutter_map_aided": ({}, ego, priors),
    }
    for name, (kwargs, egos, prior) in cases.items():
        frames, _ = synthetic_stream(world, traj, np.random.default_rng(0), **kwargs)
        tracker = LrpTracker.from_world(world, cfg.tracking)
        n, start = 0, time.perf_counter()
        while time.perf_counter() - start < seconds / len(cases):
            tracker.reset()
            for det, e, p in zip(frames, egos, prior, strict=True):
                tracker.update(det, 0.1, e, p)
            n += len(frames)
        out[f"tracker_{name}_us_per_frame"] = (time.perf_counter() - start) / n * 1e6
    return {"tracking": out}
