"""The reliability diagram draws the bins where the metrics put them."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

from lrp_gym.localization.metrics import reliability  # noqa: E402
from lrp_gym.localization.plotting import plot_reliability  # noqa: E402


def test_reliability_diagram_points_are_the_bins_of_the_metrics():
    rng = np.random.default_rng(0)
    conf = rng.uniform(0, 1, 2000)
    # calibrated by construction: a step is localised (0 m off) with probability conf
    errors_m = np.where(rng.uniform(0, 1, 2000) < conf, 0.0, 1.0)
    rows = reliability(conf, errors_m)
    fig = plot_reliability(rows)
    line = fig.axes[0].lines[1]  # after the diagonal
    x, y = line.get_data()
    kept = [r for r in rows if r["steps"] > 0]
    assert np.allclose(x, [r["mean_confidence"] for r in kept])
    assert np.allclose(y, [r["localised_share"] for r in kept])
    assert np.allclose(x, y, atol=0.08)  # calibrated data lies on the diagonal
