"""Interval code of the robustness matrix against known values."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.experiments.intervals import (
    bootstrap_interval,
    median_of,
    pooled_percentile,
    pooled_share,
    wilson_interval,
)


def _wilson_textbook(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    # Wilson (1927), as in statsmodels' proportion_confint(method="wilson"), written out here.
    p = k / n
    denom = 1 + z**2 / n
    centre = (p + z**2 / (2 * n)) / denom
    half = z * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / denom
    return centre - half, centre + half


@pytest.mark.parametrize(
    ("k", "n", "expected"),
    [
        # statsmodels.stats.proportion.proportion_confint(k, n, method="wilson")
        (0, 10, (0.0, 0.27753)),
        (5, 10, (0.23659, 0.76341)),
        (10, 10, (0.72247, 1.0)),
        (47, 50, (0.83782, 0.97936)),
    ],
)
def test_wilson_known_values(k, n, expected):
    lo, hi = wilson_interval(k, n)
    assert (lo, hi) == pytest.approx(expected, abs=5e-5)
    assert (lo, hi) == pytest.approx(_wilson_textbook(k, n), abs=1e-12)


def test_wilson_is_symmetric_and_narrows_with_more_trials():
    lo, hi = wilson_interval(3, 10)
    lo2, hi2 = wilson_interval(7, 10)
    assert lo == pytest.approx(1 - hi2) and hi == pytest.approx(1 - lo2)
    assert np.diff(wilson_interval(30, 100)) < np.diff(wilson_interval(3, 10))
    assert wilson_interval(50, 50)[0] > wilson_interval(10, 10)[0]


def test_wilson_rejects_bad_counts():
    with pytest.raises(ValueError, match="^trials: "):
        wilson_interval(0, 0)
    with pytest.raises(ValueError, match="^successes: "):
        wilson_interval(11, 10)


def test_bootstrap_of_a_constant_sample_has_zero_width():
    eps = [np.full(20, 0.07) for _ in range(12)]
    lo, hi = bootstrap_interval(eps, pooled_percentile(95), np.random.default_rng(0))
    assert lo == hi == pytest.approx(0.07)


def test_bootstrap_is_reproducible_with_a_seed_and_varies_without():
    rng = np.random.default_rng(5)
    eps = [rng.exponential(0.1, size=30) for _ in range(15)]
    a = bootstrap_interval(eps, pooled_percentile(50), np.random.default_rng(1))
    b = bootstrap_interval(eps, pooled_percentile(50), np.random.default_rng(1))
    c = bootstrap_interval(eps, pooled_percentile(50), np.random.default_rng(2))
    assert a == b and a != c
    point = pooled_percentile(50)(eps)
    assert a[0] < point < a[1]


def test_bootstrap_over_episodes_is_wider_than_over_steps_when_episodes_differ():
    # Half the episodes localised throughout, half never: the share of steps is 50 %, but
    # only 10 independent units carry that information, not 2000 steps.
    eps = [np.full(200, i % 2 == 0) for i in range(10)]
    lo, hi = bootstrap_interval(eps, pooled_share, np.random.default_rng(0))
    assert pooled_share(eps) == 0.5
    step_lo, step_hi = wilson_interval(1000, 2000)
    assert hi - lo > 5 * (step_hi - step_lo)
    assert lo < 0.3 and hi > 0.7


def test_bootstrap_mean_of_bernoulli_episodes_is_close_to_wilson():
    eps = [np.array([i < 35]) for i in range(50)]
    lo, hi = bootstrap_interval(eps, pooled_share, np.random.default_rng(3), n_resamples=4000)
    wlo, whi = wilson_interval(35, 50)
    assert lo == pytest.approx(wlo, abs=0.04) and hi == pytest.approx(whi, abs=0.04)


def test_median_skips_unobserved_and_undefined_resamples_are_dropped():
    assert median_of([None, 3, 5, None, 7]) == 5
    assert median_of([None, None]) is None
    assert bootstrap_interval([None, None], median_of, np.random.default_rng(0)) is None
    assert bootstrap_interval([], median_of, np.random.default_rng(0)) is None
