"""Path trajectory sampling and the RCS / range windows of the LRP classifier."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.radar.detections import Detections
from lrp_gym.tracking import LrpClassifier, range_limits
from lrp_gym.world.trajectory import path_trajectory


def test_paper_path_frames_land_on_the_waypoints(paper_cfg):
    path = np.asarray(paper_cfg.task.path)
    traj = path_trajectory(path, 2.0, 0.25)  # 0.5 m spacing at 2 m/s: one frame per waypoint
    assert len(traj) == len(path)
    np.testing.assert_allclose(traj.poses[:, :2], path, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(traj.velocities_xy_mps, axis=1), 2.0)
    # Heading and velocity point along the segment being entered (the last keeps its own).
    seg = np.diff(path, axis=0)
    expected = np.vstack([seg, seg[-1:]])
    np.testing.assert_allclose(
        traj.poses[:, 2], np.arctan2(expected[:, 1], expected[:, 0]), atol=1e-12
    )


def test_trajectory_spacing_and_times():
    traj = path_trajectory([[0, 0], [1, 0], [1, 1]], 0.3, 0.5)
    step = np.linalg.norm(np.diff(traj.poses[:, :2], axis=0), axis=1)
    # Straight parts advance speed * period; across the corner the chord is shorter.
    assert np.all(step <= 0.15 + 1e-12)
    np.testing.assert_allclose(step[:6], 0.15)
    np.testing.assert_allclose(np.diff(traj.times_s), 0.5)
    assert len(traj) == int(2.0 / 0.15) + 1
    with pytest.raises(ValueError):
        path_trajectory([[0, 0], [0, 0]], 1.0, 0.1)


def test_range_limits_of_the_paper_room(paper_world):
    lo, hi = range_limits(paper_world.layout, paper_world.room.size_m, 0.3, margin_m=0.0)
    assert lo == pytest.approx(3.0 - 0.3)  # reflectors at 3 m, radar at 0.3 m
    corners = np.array([[0, 0, 0.3], [5, 0, 0.3], [0, 5, 0.3], [5, 5, 0.3]])
    assert hi == pytest.approx(paper_world.layout.distances_m(corners).max())
    assert hi < paper_world.room.diagonal_m


def test_rcs_window_is_asymmetric(paper_cfg, paper_world):
    cfg = paper_cfg.tracking
    clf = LrpClassifier.from_layout(paper_world.layout, cfg, max_range_m=6.0, min_range_m=2.0)
    peak = paper_world.layout.types[0].rcs_dbsm
    low = peak - cfg.rcs_tolerance_db - cfg.rcs_pattern_loss_db
    high = peak + cfg.rcs_tolerance_db
    rcs = np.array([low + 0.1, low - 0.1, high - 0.1, high + 0.1, peak, peak, peak])
    rng_m = np.array([3.0, 3.0, 3.0, 3.0, 1.9, 6.1, 4.0])
    det = Detections(rng_m, np.zeros(7), np.zeros(7), rcs, np.zeros(7))
    np.testing.assert_array_equal(clf.candidates(det)[:, 0], [1, 0, 1, 0, 0, 0, 1])
    np.testing.assert_array_equal(clf.classify(det), [0, -1, 0, -1, -1, -1, 0])
