"""The learning curve says what its band is and carries units on its axes."""

from __future__ import annotations

import matplotlib
import numpy as np

from agents.training_io import learning_curve_figure, plot_learning_curve

matplotlib.use("Agg")


def _curve(rng):
    t = np.array([1000, 2000, 3000])
    returns = rng.normal(loc=[[1.0], [3.0], [5.0]], scale=1.0, size=(3, 10))
    successes = (rng.random((3, 10)) < 0.5).astype(float)
    return t, returns, successes


def test_band_is_one_std_over_episodes_and_labelled():
    import matplotlib.pyplot as plt

    t, returns, successes = _curve(np.random.default_rng(0))
    fig = learning_curve_figure(t, returns, successes)
    ax = fig.axes[0]
    legend = fig.axes[-1].get_legend()
    labels = [text.get_text() for text in legend.get_texts()]
    assert any("std" in lab for lab in labels), labels
    assert any("success" in lab for lab in labels), "one legend for both axes"
    band = ax.collections[0].get_paths()[0].vertices
    top = returns.mean(axis=1) + returns.std(axis=1)
    assert np.allclose(band[:, 1].max(), top.max())
    assert "[" in ax.get_xlabel() and "[" in ax.get_ylabel()
    assert "[%]" in fig.axes[1].get_ylabel()
    plt.close(fig)


def test_plot_learning_curve_writes_png(tmp_path):
    t, returns, successes = _curve(np.random.default_rng(1))
    (tmp_path / "eval").mkdir()
    np.savez(
        tmp_path / "eval" / "evaluations.npz", timesteps=t, results=returns, successes=successes
    )
    out = plot_learning_curve(tmp_path, tmp_path / "curve.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_single_evaluation_shows_its_spread():
    import matplotlib.pyplot as plt

    returns = np.array([[1.0, 3.0, 2.0, 6.0]])
    fig = learning_curve_figure(np.array([2048]), returns)
    ax = fig.axes[0]
    ys = np.concatenate([seg[:, 1] for c in ax.collections for seg in c.get_segments()])
    assert np.isclose(ys.max() - ys.min(), 2 * returns.std())
    plt.close(fig)
