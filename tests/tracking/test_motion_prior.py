"""Static-point prediction from odometry, and the distance prior from a pose estimate."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.tracking.prior import DistancePrior
from lrp_gym.tracking.range_prediction import EgoMotion, predict_static
from lrp_gym.world.robot import apply_odometry


def _range_rate(points, xy, heading, speed):
    """True distance and radial velocity of points (n, 3) from a radar at xy (height 0)."""
    diff = points - np.array([xy[0], xy[1], 0.0])
    r = np.linalg.norm(diff, axis=1)
    v = speed * np.array([np.cos(heading), np.sin(heading)])
    return r, -(diff[:, :2] @ v) / r


@pytest.fixture
def points():
    rng = np.random.default_rng(0)
    return np.column_stack([rng.uniform(-4, 4, (200, 2)), np.full(200, 2.7)])


def test_straight_drive_is_predicted_exactly(points):
    """Driving straight, the distance and rate after the move follow exactly."""
    xy, heading, speed, trans = np.array([0.3, -0.2]), 0.7, 2.0, 0.5
    r0, v0 = _range_rate(points, xy, heading, speed)
    new_xy = xy + trans * np.array([np.cos(heading), np.sin(heading)])
    r1, v1 = _range_rate(points, new_xy, heading, 1.5)  # the speed may change
    r, v, var_r, var_v = predict_static(
        r0, v0, np.full(len(r0), 2.7), speed, EgoMotion(1.5, [0.0, trans, 0.0])
    )
    np.testing.assert_allclose(r, r1, atol=1e-9)
    np.testing.assert_allclose(v, v1, atol=1e-9)
    np.testing.assert_allclose(var_r, 0.0, atol=1e-18)
    # The constant-velocity model of the paper misses by up to trans^2 / 2r abeam.
    assert np.max(np.abs(r0 + v0 * trans / speed - r1)) > 0.02


def test_a_turn_leaves_only_the_side_unknown(points):
    """After a turn the truth is one of the two sides: within one std of the mean."""
    xy, heading, speed = np.zeros(2), -1.0, 1.0
    odo = np.array([0.4, 0.5, 0.6])
    r0, v0 = _range_rate(points, xy, heading, speed)
    moved = apply_odometry(np.array([*xy, heading]), odo)
    r1, v1 = _range_rate(points, moved[:2], moved[2], 0.8)
    r, v, var_r, var_v = predict_static(r0, v0, np.full(len(r0), 2.7), speed, EgoMotion(0.8, odo))
    np.testing.assert_allclose(np.abs(r1 - r), np.sqrt(var_r), atol=1e-9)
    np.testing.assert_allclose(np.abs(v1 - v), np.sqrt(var_v), atol=1e-9)


def test_a_return_that_moves_with_the_robot_is_mispredicted():
    """The ceiling (constant range, zero Doppler) is no static point: the model says so."""
    r, v, _, _ = predict_static(
        np.array([3.7]), np.array([0.0]), np.array([2.7]), 2.0, EgoMotion(2.0, [0, 0.5, 0])
    )
    assert r[0] - 3.7 > 0.02 and v[0] > 0.2


def test_ego_motion_rejects_bad_odometry():
    with pytest.raises(ValueError, match="odometry"):
        EgoMotion(1.0, [0.0, 1.0])
    with pytest.raises(ValueError, match="speed_mps"):
        EgoMotion(float("nan"), [0.0, 0.0, 0.0])


def test_prior_from_a_certain_pose_is_the_true_distances(paper_world):
    xy = np.array([1.2, 3.4])
    prior = DistancePrior.from_pose(
        paper_world.layout, paper_world.mount_height_m, xy, np.zeros((2, 2))
    )
    np.testing.assert_allclose(prior.distance_m, paper_world.true_distances_m(xy[None]))
    np.testing.assert_allclose(prior.std_m, 0.0)


def test_prior_spread_matches_monte_carlo(paper_world):
    xy = np.array([2.0, 1.5])
    cov = np.array([[0.01, 0.004], [0.004, 0.02]])
    prior = DistancePrior.from_pose(paper_world.layout, paper_world.mount_height_m, xy, cov)
    rng = np.random.default_rng(1)
    samples = rng.multivariate_normal(xy, cov, 20000)
    d = paper_world.true_distances_m(samples)
    np.testing.assert_allclose(prior.std_m[0], d.std(axis=0), rtol=0.05)


def test_particle_prior_keeps_both_modes(paper_world):
    """A cloud split between two poses predicts both; a distance fits where a mode says."""
    a, b = np.array([1.0, 1.0]), np.array([4.0, 3.5])
    xy = np.vstack([np.tile(a, (700, 1)), np.tile(b, (300, 1))])
    prior = DistancePrior.from_particles(
        paper_world.layout, paper_world.mount_height_m, xy, np.ones(1000), max_hypotheses=100
    )
    assert prior.distance_m.shape == (100, 4)
    rows = {tuple(np.round(r, 6)) for r in prior.distance_m}
    assert len(rows) == 2  # the thinning keeps both modes
    da, db = (paper_world.true_distances_m(p[None])[0] for p in (a, b))
    np.testing.assert_allclose(np.mean(np.all(prior.distance_m == da, axis=1)), 0.7)
    var = np.full(2, 0.02**2)
    logp = prior.log_density(0, np.array([da[0], db[0]]), var)
    # Reflector 0's distance from either pose fits reflector 0, weighted by its mode.
    peak = -0.5 * np.log(2 * np.pi * (0.02**2 + 0.05**2))
    assert logp[0, 0] == pytest.approx(np.log(0.7) + peak, abs=1e-3)
    assert logp[1, 0] == pytest.approx(np.log(0.3) + peak, abs=1e-3)
    # A distance far from both predictions of reflector 1 does not fit it.
    assert prior.log_density(0, np.array([9.0]), var[:1])[0, 1] < -100


def test_particle_prior_rejects_bad_input(paper_world):
    with pytest.raises(ValueError, match="weights"):
        DistancePrior.from_particles(
            paper_world.layout, paper_world.mount_height_m, np.zeros((3, 2)), np.zeros(3)
        )
