"""Figure of how far the localiser's confidence can be believed (a reliability diagram)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

#: Normal quantile of the 95 % Wilson intervals drawn around each bin's share.
Z95 = 1.96
#: Lowest mean confidence whose claimed miss rate (1 - c) the right-hand panel draws.
CLAIM_FROM = 0.5


def wilson_interval(share: np.ndarray, steps: np.ndarray, z: float = Z95):
    """95 % Wilson score interval ``(low, high)`` of a share observed over ``steps`` trials:
    small bins are not over-read, and a share of 0 still has an upper bound."""
    share, steps = np.asarray(share, float), np.asarray(steps, float)
    centre = (share + z**2 / (2 * steps)) / (1 + z**2 / steps)
    half = z * np.sqrt(share * (1 - share) / steps + z**2 / (4 * steps**2)) / (1 + z**2 / steps)
    # The interval holds the share; at a share of 0 or 1 rounding could put it just outside.
    return np.minimum(centre - half, share), np.maximum(centre + half, share)


def plot_reliability(rows: Sequence[dict[str, Any]], title: str = "", localised_m: float = 0.2):
    """Reliability diagram of ``info["localization_confidence"]``.

    ``rows`` are the bins of :func:`lrp_gym.localization.metrics.reliability` (``lo``, ``hi``,
    ``steps``, ``mean_confidence``, ``localised_share``, ``wrong_share``). Left: a calibrated
    confidence puts every bin on the diagonal (among the steps with confidence about c, a
    share c is localised). Right, on log axes: the confident bins' claim, 1 - c, against the
    share of their steps that is wrong (off by more than 0.3 m); a bin above the diagonal is
    overconfident, and a bin with no wrong step is drawn at the upper end of its interval
    (a triangle). Bars: the share of steps per bin, so that a well-placed but empty bin is
    not taken for evidence. Returns the matplotlib figure; ``fig.axes`` is (diagram, claims,
    bars).
    """
    import matplotlib.pyplot as plt

    rows = [r for r in rows if r["steps"] > 0]
    fig = plt.figure(figsize=(9.0, 5.6))
    grid = fig.add_gridspec(2, 2, height_ratios=[3, 1])
    ax = fig.add_subplot(grid[0, 0])
    ax_claim = fig.add_subplot(grid[:, 1])
    ax_n = fig.add_subplot(grid[1, 0], sharex=ax)
    ax.plot([0, 1], [0, 1], "--", color="0.5", lw=1, label="calibrated")
    if rows:
        conf = np.array([r["mean_confidence"] for r in rows])
        share = np.array([r["localised_share"] for r in rows])
        steps = np.array([r["steps"] for r in rows])
        low, high = wilson_interval(share, steps)
        ax.errorbar(
            conf, share, yerr=[share - low, high - share], fmt="o-", capsize=3,
            label="AMCL (95 % interval)",
        )  # fmt: skip
        lo = np.array([r["lo"] for r in rows])
        hi = np.array([r["hi"] for r in rows])
        ax_n.bar((lo + hi) / 2, steps / steps.sum(), width=(hi - lo) * 0.9, color="C0", alpha=0.6)
        _draw_claims(ax_claim, rows)
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.02)
    ax.set_ylabel(f"share of steps localised (< {localised_m:g} m)")
    fig.suptitle(title or "Reliability of the localisation confidence", fontsize=10)
    ax.set_title("Share localised per confidence bin", fontsize=10)
    ax.legend(loc="upper left")
    ax.grid(alpha=0.3)
    ax_n.set_xlabel("localisation confidence")
    ax_n.set_ylabel("share of steps")
    ax_n.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def _draw_claims(ax, rows: Sequence[dict[str, Any]]) -> None:
    """The confident bins' claimed miss rate 1 - c against their observed wrong share."""
    rows = [
        r for r in rows if r["mean_confidence"] >= CLAIM_FROM and r.get("wrong_share") is not None
    ]
    floor = 1e-4
    ax.plot([floor, 1], [floor, 1], "--", color="0.5", lw=1, label="as claimed")
    if rows:
        claim = np.maximum(1.0 - np.array([r["mean_confidence"] for r in rows]), floor)
        wrong = np.array([r["wrong_share"] for r in rows])
        steps = np.array([r["steps"] for r in rows])
        low, high = wilson_interval(wrong, steps)
        seen = wrong > 0
        ax.errorbar(
            claim[seen], wrong[seen], yerr=[wrong[seen] - low[seen], high[seen] - wrong[seen]],
            fmt="o", capsize=3, color="C3", label="wrong (> 0.3 m), 95 % interval",
        )  # fmt: skip
        ax.plot(claim[~seen], high[~seen], "v", color="C3", mfc="none", label="none wrong: bound")
        for c, w, r in zip(claim, np.where(seen, wrong, high), rows, strict=True):
            if r["lo"] < 0.8:  # the unconfident bins crowd the top right; the bars name them
                continue
            ax.annotate(f"{r['lo']:g}-{r['hi']:g}", (c, w), fontsize=7, xytext=(4, 3),
                        textcoords="offset points")  # fmt: skip
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(floor, 1)
    ax.set_ylim(floor, 1)
    ax.set_xlabel("claimed miss rate, 1 - mean confidence of the bin")
    ax.set_ylabel("share of the bin's steps off by > 0.3 m")
    ax.set_title("Confident bins: claim against outcome", fontsize=10)
    ax.legend(loc="upper left", fontsize=8)
    ax.grid(alpha=0.3, which="both")
