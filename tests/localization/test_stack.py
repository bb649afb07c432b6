"""One frame through the localisation stack: the order and what feeds what."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.envs.nav_env import LRPRadarNavEnv
from lrp_gym.experiments.track_path import ego_motions
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.stack import LocalizationStack
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.tracking.prior import DistancePrior
from lrp_gym.tracking.tracker import LrpTracker
from lrp_gym.world import OdometryNoise, noisy_odometry, odometry_delta
from lrp_gym.world.trajectory import path_trajectory
from lrp_gym.world.world import World


def small_stack(cfg, world, measurements, map_aided):
    loc = cfg.localization.model_copy(update={"initial_particles": 2000, "max_particles": 2000})
    return LocalizationStack(
        world,
        RadarSensor(world, cfg.radar),
        LrpTracker.from_world(world, cfg.tracking),
        Amcl(world, loc),
        dt_s=0.25,
        measurements=measurements,
        map_aided=map_aided,
    )


def drive(cfg, world, measurements, map_aided, frames=8):
    stack = small_stack(cfg, world, measurements, map_aided)
    traj = path_trajectory(np.asarray(cfg.task.path), cfg.robot.max_speed_mps, 0.25)
    rng = np.random.default_rng(3)
    egos = ego_motions(traj, world, np.random.default_rng(4))
    stack.reset(rng, None)
    return [
        stack.step(traj.poses[k], traj.velocities_xy_mps[k], egos[k].odometry, rng)
        for k in range(frames)
    ]


def test_amcl_on_detections_does_not_depend_on_the_tracker(paper_cfg, paper_world):
    """With measurements=detections the tracker only reads AMCL: same estimates either way."""
    aided = drive(paper_cfg, paper_world, "detections", True)
    plain = drive(paper_cfg, paper_world, "detections", False)
    for a, b in zip(aided, plain, strict=True):
        np.testing.assert_array_equal(a.localizer_estimate.pose, b.localizer_estimate.pose)
    # ... while the fingerprints do differ: the prior changed which tracks are reported.
    assert any(
        not np.array_equal(a.fingerprint.distances_m[0], b.fingerprint.distances_m[0])
        for a, b in zip(aided, plain, strict=True)
    )


@pytest.mark.parametrize("measurements", ["detections", "tracks"])
def test_fingerprint_never_exceeds_the_layout(paper_cfg, paper_world, measurements):
    for res in drive(paper_cfg, paper_world, measurements, True):
        assert len(res.fingerprint.distances_m[0]) <= 4
        assert np.all(np.isfinite(res.estimate.pose))
        # Without a look-up table the consumer's estimate is the localiser's.
        assert res.estimate is res.localizer_estimate and res.lut_estimate is None


def test_tracker_is_identified_by_this_frames_posterior(paper_cfg, paper_world):
    """measurements=detections: AMCL first, then its new cloud ranks the tracks.

    A second tracker fed the same detections with a prior from the cloud *after* each
    frame's update reports exactly the stack's fingerprints; the cloud of the previous frame
    would not.
    """
    world = paper_world
    stack = small_stack(paper_cfg, world, "detections", True)
    replica = LrpTracker.from_world(world, paper_cfg.tracking)
    traj = path_trajectory(np.asarray(paper_cfg.task.path), paper_cfg.robot.max_speed_mps, 0.25)
    egos = ego_motions(traj, world, np.random.default_rng(4))
    rng = np.random.default_rng(3)
    stack.reset(rng, traj.poses[0])  # converged from the start: the prior ranks the tracks
    differs_from_previous_cloud = False
    for k in range(len(traj)):
        before = stack.localizer.particles[:, :2].copy(), stack.localizer.weights.copy()
        res = stack.step(traj.poses[k], traj.velocities_xy_mps[k], egos[k].odometry, rng)
        loc = stack.localizer
        prior = DistancePrior.from_particles(
            world.layout,
            world.mount_height_m,
            loc.particles[:, :2],
            loc.weights,
            confident=res.localizer_estimate.converged,
        )
        fp = replica.update(res.detections, 0.25, egos[k], prior)
        for mine, theirs in zip(fp.distances_m, res.fingerprint.distances_m, strict=True):
            np.testing.assert_array_equal(mine, theirs)
        differs_from_previous_cloud |= not np.array_equal(before[0], loc.particles[:, :2])
    assert differs_from_previous_cloud


def test_env_rollout_is_the_stack_with_odometry_drawn_before_the_radar():
    """The env is reset, odometry noise, then one stack step per frame, all from its seed:
    the localiser from the seed's generator, the sensing from the first of two children
    spawned after the reset (the second is the perturbations')."""
    env = LRPRadarNavEnv(radar_fidelity="detections", task_mode="path")
    seed, speed_frac = 11, 0.5
    env.reset(seed=seed)
    infos = [env.unwrapped._info(collided=False, reached=False, rewards=None)]
    for _ in range(6):
        _, _, terminated, _, info = env.step(np.array([speed_frac, 0.0]))
        assert not terminated
        infos.append(info)
    world = env.world
    stack = LocalizationStack.from_config(world, env.cfg)
    rng = np.random.default_rng(seed)  # what gymnasium seeds np_random with
    stack.reset(rng, None)
    sensing, _ = rng.spawn(2)
    speed = speed_frac * world.robot.max_speed_mps
    prev = None
    for info in infos:
        pose = info["true_pose"]
        vel = np.zeros(2) if prev is None else speed * np.array([np.cos(pose[2]), np.sin(pose[2])])
        odo = noisy_odometry(world.odometry_noise, prev, pose, sensing)
        res = stack.step(pose, vel, odo, rng, sensing_rng=sensing)
        np.testing.assert_array_equal(res.estimate.pose, info["est_pose"])
        assert len(res.detections) == info["n_detections"]
        prev = pose


def test_noisy_odometry_first_frame_draws_nothing():
    rng = np.random.default_rng(0)
    state = rng.bit_generator.state
    np.testing.assert_array_equal(
        noisy_odometry(OdometryNoise(0.1, 0.05), None, np.ones(3), rng), np.zeros(3)
    )
    assert rng.bit_generator.state == state
    prev, pose = np.array([0.0, 0.0, 0.1]), np.array([0.3, 0.4, 0.5])
    exact = OdometryNoise(0.0, 0.0)
    np.testing.assert_allclose(noisy_odometry(exact, prev, pose, rng), odometry_delta(prev, pose))
    assert rng.bit_generator.state != state  # a move draws, even at zero noise


def test_a_second_suspect_drops_from_the_full_surveyed_map(paper_cfg):
    """Reflectors dropped one after the other: each model comes from the full map, so the
    survey's per-reflector scaling follows the layout indices (the second suspect crashed on
    the first one's reduced survey)."""
    from lrp_gym.localization.visibility import RadarLink

    xy = [[0.9, 1.3], [3.8, 0.7], [4.3, 3.6], [1.6, 4.4], [2.5, 0.6], [0.7, 3.0]]
    layout = [{"position": [x, y, 3.0], "type": "A"} for x, y in xy]
    cfg = paper_cfg.with_overrides({"reflectors": {"layout": layout}})
    world = World.from_config(cfg)
    sensor = RadarSensor(world, cfg.radar)
    rates = np.array([0.2, 0.3, 0.4, 0.5, 0.6, 0.7])
    link = RadarLink.from_sensor(sensor).surveyed(rates, 0.8)
    tracker = LrpTracker.from_world(world, cfg.tracking)
    amcl = Amcl(world, cfg.localization, link)
    stack = LocalizationStack(world, sensor, tracker, amcl, dt_s=0.25)
    full = stack.localizer.model
    stack.drop_reflectors((1,))
    np.testing.assert_array_equal(
        stack.localizer.model.link.delivery, link.delivery[[0, 2, 3, 4, 5]]
    )
    stack.drop_reflectors((1, 4))
    model = stack.localizer.model
    np.testing.assert_array_equal(model.link.delivery, link.delivery[[0, 2, 3, 5]])
    assert sum(model.counts) == 4
    stack.drop_reflectors(())
    assert stack.localizer.model is full
