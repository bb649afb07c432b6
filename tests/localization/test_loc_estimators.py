import numpy as np
import pytest

from lrp_gym.localization.particle_statistics import (
    best_k_mean,
    circular_mean,
    circular_variance_rad2,
    cluster_mean,
    pose_covariance,
)


def test_circular_mean_wraps_around_pi():
    a = np.array([np.pi - 0.1, -np.pi + 0.1, np.pi - 0.05, -np.pi + 0.05])
    m = circular_mean(a)
    assert abs(abs(m) - np.pi) < 1e-9  # the naive mean would be 0
    assert circular_mean(np.array([-0.2, 0.4]), np.array([2.0, 1.0])) == pytest.approx(
        0.0, abs=1e-2
    )


def test_circular_variance_small_spread_and_uniform():
    rng = np.random.default_rng(0)
    a = 3.1 + 0.05 * rng.standard_normal(200_000)
    a = (a + np.pi) % (2 * np.pi) - np.pi  # straddles the wrap
    assert circular_variance_rad2(a) == pytest.approx(0.05**2, rel=0.02)
    assert circular_variance_rad2(rng.uniform(-np.pi, np.pi, 100_000)) > 10.0


def test_pose_covariance_heading_cross_terms_wrap():
    rng = np.random.default_rng(1)
    n = 50_000
    dx = 0.1 * rng.standard_normal(n)
    th = np.pi - 0.02 + 0.2 * dx  # correlated with x, wrapping past pi
    p = np.column_stack(
        [1.0 + dx, 2.0 + 0.03 * rng.standard_normal(n), (th + np.pi) % (2 * np.pi) - np.pi]
    )
    cov = pose_covariance(p, np.ones(n), np.array([1.0, 2.0, np.pi - 0.02]))
    assert cov[0, 0] == pytest.approx(0.01, rel=0.03)
    assert cov[1, 1] == pytest.approx(0.03**2, rel=0.03)
    assert cov[0, 2] == pytest.approx(0.2 * 0.01, rel=0.05)
    assert cov[2, 2] == pytest.approx(0.2**2 * 0.01, rel=0.05)
    np.testing.assert_allclose(cov, cov.T)


def test_best_k_mean_uses_k_heaviest_near_the_best():
    p = np.array(
        [[1.0, 1.0, 0.0], [1.1, 1.0, 0.0], [1.0, 1.1, 0.0], [1.05, 1.05, 0.0], [4.0, 4.0, 0.0]]
    )
    w = np.array([0.3, 0.2, 0.2, 0.01, 0.29])
    est = best_k_mean(p, w, k=3, radius_m=0.15)
    expected = (0.3 * p[0] + 0.2 * p[1] + 0.2 * p[2]) / 0.7
    np.testing.assert_allclose(est[:2], expected[:2])


def test_cluster_mean_picks_heaviest_cluster_with_wrapped_heading():
    rng = np.random.default_rng(2)
    a = np.column_stack(
        [
            1 + 0.03 * rng.standard_normal(300),
            1 + 0.03 * rng.standard_normal(300),
            np.where(rng.random(300) < 0.5, np.pi - 0.05, -np.pi + 0.05),
        ]
    )
    b = np.column_stack(
        [4 + 0.03 * rng.standard_normal(100), 4 + 0.03 * rng.standard_normal(100), np.zeros(100)]
    )
    p = np.vstack([a, b])
    w = np.r_[np.full(300, 1.0), np.full(100, 4.0)]  # b: fewer particles, more weight
    est = cluster_mean(p, w, 0.1, np.array([5.0, 5.0]))
    assert np.hypot(est[0] - 4, est[1] - 4) < 0.02
    w2 = np.r_[np.full(300, 1.0), np.full(100, 1.0)]
    est2 = cluster_mean(p, w2, 0.1, np.array([5.0, 5.0]))
    assert np.hypot(est2[0] - 1, est2[1] - 1) < 0.02
    assert abs(abs(est2[2]) - np.pi) < 1e-6
