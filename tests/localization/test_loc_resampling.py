import numpy as np
import pytest

from lrp_gym.localization.resampling import effective_sample_size, systematic_resample


@pytest.mark.parametrize("n", [1, 7, 100, 1000])
def test_systematic_counts_are_floor_or_ceil_of_expected(n):
    rng = np.random.default_rng(3)
    w = rng.random(50) ** 4
    w /= w.sum()
    for _ in range(20):
        idx = systematic_resample(w, n, rng)
        assert len(idx) == n
        assert np.all(np.diff(idx) >= 0)
        counts = np.bincount(idx, minlength=len(w))
        expected = n * w
        assert np.all(counts >= np.floor(expected) - 1e-9)
        assert np.all(counts <= np.ceil(expected) + 1e-9)


def test_systematic_matches_searchsorted_reference():
    rng = np.random.default_rng(0)
    w = rng.random(300)
    w[::7] = 0.0
    w /= w.sum()
    state = rng.bit_generator.state
    idx = systematic_resample(w, 500, rng)
    rng.bit_generator.state = state
    u = rng.random()
    ref = np.searchsorted(np.cumsum(w), (u + np.arange(500)) / 500, side="right")
    np.testing.assert_array_equal(idx, np.minimum(ref, len(w) - 1))
    assert not np.any(np.isin(idx, np.flatnonzero(w == 0)))


def test_expected_counts_unbiased_over_draws():
    rng = np.random.default_rng(1)
    w = np.array([0.05, 0.15, 0.3, 0.5])
    mean = np.mean(
        [np.bincount(systematic_resample(w, 10, rng), minlength=4) for _ in range(4000)], 0
    )
    np.testing.assert_allclose(mean, 10 * w, atol=0.05)


def test_effective_sample_size():
    assert effective_sample_size(np.full(40, 1 / 40)) == pytest.approx(40)
    one_hot = np.zeros(40)
    one_hot[3] = 1.0
    assert effective_sample_size(one_hot) == pytest.approx(1.0)
