"""The reliability diagram draws the bins where the metrics put them."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

from lrp_gym.localization.metrics import reliability  # noqa: E402
from lrp_gym.localization.plotting import plot_reliability, wilson_interval  # noqa: E402


def _calibrated(n: int = 50_000):
    rng = np.random.default_rng(0)
    conf = rng.uniform(0, 1, n)
    # calibrated by construction: a step is right (0 m off) with probability conf, else 1 m off
    return conf, np.where(rng.uniform(0, 1, n) < conf, 0.0, 1.0)


def test_reliability_diagram_points_are_the_bins_of_the_metrics():
    rows = reliability(*_calibrated())
    fig = plot_reliability(rows)
    line = fig.axes[0].lines[1]  # after the diagonal
    x, y = line.get_data()
    kept = [r for r in rows if r["steps"] > 0]
    assert np.allclose(x, [r["mean_confidence"] for r in kept])
    assert np.allclose(y, [r["localised_share"] for r in kept])
    assert np.allclose(x, y, atol=0.05)  # calibrated data lies on the diagonal


def test_claims_panel_puts_the_confident_bins_on_its_diagonal_when_calibrated():
    rows = reliability(*_calibrated(400_000))
    fig = plot_reliability(rows)
    claims = fig.axes[1]
    x, y = claims.lines[1].get_data()  # the bins with wrong steps, after the diagonal
    confident = [r for r in rows if r["mean_confidence"] >= 0.5]
    assert np.allclose(x, [1 - r["mean_confidence"] for r in confident])
    assert np.allclose(y, [r["wrong_share"] for r in confident])
    # calibrated: each bin's claim lies within its wrong share's 3-sigma interval
    low, high = wilson_interval(y, np.array([r["steps"] for r in confident]), z=3.0)
    assert np.all((low <= x) & (x <= high)), (low, x, high)
    # and an overconfident bin would not: twice the claim is outside for the busy bins
    assert np.all(2 * x[:-1] > high[:-1])


def test_bins_all_right_or_all_wrong_are_drawn_with_their_bounds():
    # Every step localised (share 1, wrong share 0): the intervals still hold the shares, and
    # the confident bins appear as upper bounds on the claims panel.
    conf = np.concatenate([np.full(300, 0.97), np.full(700, 0.999), np.full(50, 0.3)])
    errors = np.concatenate([np.zeros(1000), np.full(50, 1.0)])
    rows = reliability(conf, errors)
    fig = plot_reliability(rows)
    bounds = fig.axes[1].lines[-1]  # the open triangles: bins with no wrong step
    x, y = bounds.get_data()
    assert np.allclose(x, [0.03, 0.001])
    low, high = wilson_interval(np.zeros(2), np.array([300, 700]))
    assert np.allclose(y, high) and np.all(low == 0.0) and np.all(y < 0.02)
