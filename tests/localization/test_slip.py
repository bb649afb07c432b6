"""Wheel-slip-aware motion noise (lrp_gym.localization.slip, localization.slip_adaptive)."""

from __future__ import annotations

import numpy as np

from lrp_gym.config import load_scenario
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.particle_motion import odometry_noise
from lrp_gym.localization.slip import SlipMonitor
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world import World
from lrp_gym.world.robot import apply_odometry, odometry_delta

STEP = np.array([0.0, 0.35, 0.0])  # a frame of straight driving


def _monitor(max_inflation: float = 4.0) -> SlipMonitor:
    return SlipMonitor(odometry_noise(load_scenario("ipin2023").localization), max_inflation)


def test_consistent_odometry_keeps_the_noise_and_slip_inflates_it() -> None:
    rng = np.random.default_rng(0)
    mon = _monitor()
    sigma = mon.base.std(STEP)
    pose = np.zeros(3)
    for _ in range(30):  # corrections within the model's own noise
        pose = apply_odometry(pose, STEP) + rng.normal(0.0, 0.5) * np.array([sigma[1], 0, 0])
        mon.update(STEP, pose, True)
        assert mon.scale < 1.3
    for _ in range(10):  # the wheels report 0.35 m, the robot went 0.6 m
        pose = apply_odometry(pose, STEP * 0.6 / 0.35)
        mon.update(STEP, pose, True)
    assert mon.scale > 2.0
    inflated = mon.noise()
    assert inflated.sigma_distance_m == mon.base.sigma_distance_m * mon.scale
    for _ in range(20):  # agreeing again: back to the model
        pose = apply_odometry(pose, STEP)
        mon.update(STEP, pose, True)
    assert mon.scale < 1.2


def test_capped_and_only_judged_on_converged_frames() -> None:
    mon = _monitor(max_inflation=2.5)
    pose = np.zeros(3)
    for _ in range(20):
        pose = apply_odometry(pose, STEP * 3.0)
        mon.update(STEP, pose, True)
    assert mon.scale == 2.5
    mon.reset()
    for _ in range(20):  # a lost filter's jumps say nothing about the wheels
        pose = apply_odometry(pose, STEP * 3.0)
        mon.update(STEP, pose, False)
    assert mon.scale == 1.0


def _track(slip_adaptive: bool, seed: int) -> float:
    """Mean error of AMCL on exact distances around a loop whose odometry reports 60 % of the
    distance driven and turns 4 degrees less per frame."""
    cfg = load_scenario("ipin2023")
    world = World.from_config(cfg)
    loc = cfg.localization.model_copy(
        update={"slip_adaptive": slip_adaptive, "initial_particles": 2000, "max_particles": 2000}
    )
    amcl = Amcl(world, loc)
    rng = np.random.default_rng(seed)
    phi = np.linspace(0.0, 2.0 * np.pi, 41)
    poses = np.column_stack([2.5 + 1.4 * np.cos(phi), 2.5 + 1.4 * np.sin(phi), phi + np.pi / 2])
    amcl.reset(rng, poses[0])
    errors = []
    for prev, pose in zip(poses[:-1], poses[1:], strict=True):
        true = odometry_delta(prev, pose)
        reported = np.array([true[0] - np.deg2rad(2.0), 0.6 * true[1], true[2] - np.deg2rad(2.0)])
        fp = Fingerprint.from_true(world.layout, world.radar_position(pose[:2]), std_m=0.03)
        est = amcl.update(reported, fp, rng)
        errors.append(np.hypot(*(est.pose[:2] - pose[:2])))
    return float(np.mean(errors[10:]))


def test_amcl_with_slip_tracks_better_than_without() -> None:
    off = [_track(False, s) for s in range(3)]
    on = [_track(True, s) for s in range(3)]
    assert np.mean(on) < 0.8 * np.mean(off), (on, off)
