"""One frame through tracker and AMCL: the order and what feeds what."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.experiments.track_path import ego_motions
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.pipeline import track_and_localize
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.tracking.tracker import LrpTracker
from lrp_gym.world.trajectory import path_trajectory


def drive(cfg, world, measurements, map_aided, frames=8):
    sensor = RadarSensor(world, cfg.radar)
    traj = path_trajectory(np.asarray(cfg.task.path), cfg.robot.max_speed_mps, 0.25)
    rng = np.random.default_rng(3)
    egos = ego_motions(traj, world, np.random.default_rng(4))
    tracker = LrpTracker.from_world(world, cfg.tracking)
    loc = cfg.localization.model_copy(update={"initial_particles": 2000, "max_particles": 2000})
    amcl = Amcl(world, loc)
    amcl.reset(rng, None)
    est, out = None, []
    for k in range(frames):
        det = sensor.measure(traj.poses[k], traj.velocities_xy_mps[k], rng)
        fp, est = track_and_localize(
            world,
            tracker,
            amcl,
            det,
            0.25,
            egos[k],
            est,
            rng,
            measurements=measurements,
            map_aided=map_aided,
        )
        out.append((fp, est))
    return out


def test_amcl_on_detections_does_not_depend_on_the_tracker(paper_cfg, paper_world):
    """With measurements=detections the tracker only reads AMCL: same estimates either way."""
    aided = drive(paper_cfg, paper_world, "detections", True)
    plain = drive(paper_cfg, paper_world, "detections", False)
    for (_, a), (_, b) in zip(aided, plain, strict=True):
        np.testing.assert_array_equal(a.pose, b.pose)
    # ... while the fingerprints do differ: the prior changed which tracks are reported.
    assert any(
        not np.array_equal(fa.distances_m[0], fb.distances_m[0])
        for (fa, _), (fb, _) in zip(aided, plain, strict=True)
    )


@pytest.mark.parametrize("measurements", ["detections", "tracks"])
def test_fingerprint_never_exceeds_the_layout(paper_cfg, paper_world, measurements):
    for fp, est in drive(paper_cfg, paper_world, measurements, True):
        assert len(fp.distances_m[0]) <= 4
        assert np.all(np.isfinite(est.pose))
