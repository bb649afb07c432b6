"""CFAR: the candidate path agrees with full-map thresholds and keeps the design Pfa."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import maximum_filter, rank_filter

from lrp_gym.radar.cfar import Cfar2D
from lrp_gym.radar.processing import RangeDopplerProcessor
from lrp_gym.waveform import FmcwParameters

WINDOWS = [((2, 1), (8, 3)), ((0, 0), (3, 0)), ((1, 1), (4, 2))]


def _map(seed=0):
    rng = np.random.default_rng(seed)
    m = rng.exponential(1.0, (256, 32))
    m[100, 5], m[101:104, 5], m[250, 31] = 1e4, 300.0, 50.0
    return m


@pytest.mark.parametrize("method", ["CA", "SO", "GO", "OS"])
@pytest.mark.parametrize(("guard", "train"), WINDOWS)
def test_threshold_at_matches_full_map(method, guard, train):
    cfar = Cfar2D(method, guard, train, 1e-3, 0.75)
    m = _map()
    rows, cols = np.divmod(np.arange(m.size), m.shape[1])
    at = cfar.threshold_at(cfar.pad(m), rows, cols).reshape(m.shape)
    np.testing.assert_allclose(at, cfar.threshold(m), rtol=1e-9)


def test_os_matches_scipy_rank_filter():
    cfar = Cfar2D("OS", (2, 1), (8, 3), 1e-4, 0.6)
    m = _map(1)
    (g0, g1), (h0, h1) = cfar.guard, cfar.half_window
    foot = np.ones((2 * h0 + 1, 2 * h1 + 1), bool)
    foot[h0 - g0 : h0 + g0 + 1, h1 - g1 : h1 + g1 + 1] = False
    padded = np.pad(np.pad(m, ((h0, h0), (0, 0)), mode="symmetric"), ((0, 0), (h1, h1)), "wrap")
    ref = rank_filter(padded, rank=cfar.rank - 1, footprint=foot)[h0:-h0, h1:-h1]
    np.testing.assert_allclose(cfar.threshold(m), cfar.alpha * ref, rtol=1e-12)


@pytest.mark.parametrize("method", ["CA", "SO", "GO", "OS"])
def test_prethreshold_is_safe(method):
    cfar = Cfar2D(method, (2, 1), (8, 3), 1e-6, 0.75)
    q = cfar.prethreshold_fraction
    assert q > 0.0
    assert cfar.statistic_cdf(q) <= 1e-3 * cfar.pfa
    # the statistic's CDF is right: Monte Carlo median of S on unit noise
    rng = np.random.default_rng(0)
    s = [cfar.threshold(m)[10:-10] / cfar.alpha for m in rng.exponential(1.0, (30, 64, 32))]
    med = float(np.median(s))
    assert 0.4 < cfar.statistic_cdf(med) < 0.6


@pytest.mark.parametrize("method", ["CA", "SO", "GO", "OS"])
def test_false_alarm_rate_full_map_and_candidate_path(method):
    pfa = 1e-3
    cfar = Cfar2D(method, (2, 1), (8, 3), pfa, 0.75)
    rng = np.random.default_rng(3)
    maps = rng.exponential(1.0, (40, 256, 32))
    fa = np.mean([cfar.detect(m).mean() for m in maps])
    assert 0.5 * pfa < fa < 2 * pfa, fa
    # candidate path (local maxima above the pre-threshold) = full map at local maxima
    fm = FmcwParameters(60e9, 2e9, 220e-6, 256, 32)
    proc = RangeDopplerProcessor(fm, "hann", cfar)
    pre = cfar.alpha * cfar.prethreshold_fraction
    n_cand, n_full = 0, 0
    for m in maps[:20]:
        n_cand += len(proc.peaks(m, 0.0, pre).range_bin)
        local = m >= maximum_filter(m, size=3, mode=("nearest", "wrap"))
        hit = (m > cfar.threshold(m)) & local
        hit[0] = False
        n_full += int(hit.sum())
    assert n_cand == n_full
    assert n_full > 0
