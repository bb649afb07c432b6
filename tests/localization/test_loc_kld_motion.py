import numpy as np
import pytest
from scipy.stats import chi2

from lrp_gym.localization.kld import KldBinner, kld_particle_count
from lrp_gym.localization.particle_motion import sample_motion, standard_normals32
from lrp_gym.world.robot import OdometryNoise, apply_odometry


@pytest.mark.parametrize("k", [10, 50, 200, 2000])
def test_kld_count_approximates_chi_square_quantile(k):
    exact = chi2.ppf(0.99, k - 1) / (2 * 0.05)
    assert kld_particle_count(k, 0.05, 0.99) == pytest.approx(exact, rel=0.01)


def test_kld_count_one_bin_and_monotone():
    assert kld_particle_count(1, 0.05, 0.99) == 0
    assert kld_particle_count(0, 0.05, 0.99) == 0
    counts = [kld_particle_count(k, 0.05, 0.99) for k in range(2, 300)]
    assert np.all(np.diff(counts) > 0)
    # The quantile enters as a normal quantile: a higher confidence needs more particles.
    assert kld_particle_count(50, 0.05, 0.999) > kld_particle_count(50, 0.05, 0.5)


def test_binner_counts_distinct_bins():
    b = KldBinner(np.array([5.0, 5.0]), 0.1, np.deg2rad(10.0))
    p = np.array(
        [
            [0.01, 0.01, 0.0],
            [0.02, 0.05, 0.01],
            [0.15, 0.01, 0.0],
            [0.01, 0.01, np.pi - 1e-3],
            [0.01, 0.01, -np.pi],
            [4.99, 4.99, 0.0],
        ]
    )
    assert b.count(p) == 5
    assert b.count(p, np.array([0, 1, 1, 0])) == 1
    assert b.count(p) == 5  # flags are cleared between calls


def test_normals32_moments():
    x = standard_normals32(np.random.default_rng(0), 400_001).astype(float)
    assert len(x) == 400_001
    assert abs(x.mean()) < 0.01
    assert x.std() == pytest.approx(1.0, abs=0.01)
    assert np.mean(x**4) == pytest.approx(3.0, abs=0.05)


def test_motion_without_noise_equals_apply_odometry():
    rng = np.random.default_rng(1)
    p = np.column_stack([rng.random((100, 2)) * 5, rng.uniform(-np.pi, np.pi, 100)])
    od = np.array([0.7, 0.5, -2.9])
    got = sample_motion(p, od, OdometryNoise(0.0, 0.0), rng)
    np.testing.assert_allclose(got, apply_odometry(p, np.broadcast_to(od, p.shape)), atol=1e-6)
    assert np.all((got[:, 2] >= -np.pi) & (got[:, 2] < np.pi))


def test_motion_noise_statistics():
    rng = np.random.default_rng(2)
    n = 200_000
    p = np.zeros((n, 3))
    noise = OdometryNoise(np.deg2rad(5.0), 0.05)
    got = sample_motion(p, np.array([0.0, 0.5, 0.0]), noise, rng)
    trans = np.hypot(got[:, 0], got[:, 1])
    assert trans.mean() == pytest.approx(0.5, abs=2e-3)
    assert trans.std() == pytest.approx(0.05, rel=0.02)
    # heading = rot1 noise + rot2 noise: std sqrt(2) * 5 deg
    assert got[:, 2].std() == pytest.approx(np.sqrt(2) * np.deg2rad(5.0), rel=0.02)
