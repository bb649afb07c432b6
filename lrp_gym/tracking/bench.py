"""Speed of the tracker per frame on synthetic streams (``lrp-gym bench`` style entry point)."""

from __future__ import annotations

import time

import numpy as np

from lrp_gym.config import ScenarioConfig
from lrp_gym.tracking.synthetic import synthetic_stream
from lrp_gym.tracking.tracker import LrpTracker
from lrp_gym.world.trajectory import path_trajectory
from lrp_gym.world.world import World

LOOP_FRACTIONS = [[0.15, 0.15], [0.85, 0.15], [0.85, 0.85], [0.15, 0.85], [0.15, 0.25]]


def bench_tracking(cfg: ScenarioConfig, seconds: float) -> dict:
    """Mean time per :meth:`LrpTracker.update` in microseconds, clean and with clutter.

    The robot loops around the room at 1 m/s with 0.1 s frames; "clean" has every reflector
    detected and no clutter, "clutter" misses 20 % of them and adds 2 reflector-like clutter
    detections per frame on average.
    """
    world = World.from_config(cfg)
    path = np.asarray(LOOP_FRACTIONS) * world.room.size_m[:2]
    traj = path_trajectory(path, 1.0, 0.1)
    out = {}
    cases = {"clean": dict(miss_probability=0.0, clutter_per_frame=0.0), "clutter": {}}
    for name, kwargs in cases.items():
        frames, _ = synthetic_stream(world, traj, np.random.default_rng(0), **kwargs)
        tracker = LrpTracker.from_world(world, cfg.tracking)
        n, start = 0, time.perf_counter()
        while time.perf_counter() - start < seconds / len(cases):
            tracker.reset()
            for det in frames:
                tracker.update(det, 0.1)
            n += len(frames)
        out[f"tracker_{name}_us_per_frame"] = (time.perf_counter() - start) / n * 1e6
    return {"tracking": out}
