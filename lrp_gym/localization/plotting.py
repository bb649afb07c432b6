"""Figure of how far the localiser's confidence can be believed (a reliability diagram)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np


def plot_reliability(rows: Sequence[dict[str, Any]], title: str = "", localised_m: float = 0.2):
    """Reliability diagram of ``info["localization_confidence"]``.

    ``rows`` are the bins of :func:`lrp_gym.localization.metrics.reliability` (``lo``, ``hi``,
    ``steps``, ``mean_confidence``, ``localised_share``). A calibrated confidence puts every
    bin on the diagonal: among the steps with confidence about c, a share c is localised.
    Bars show the share of steps per bin, so that a well-placed but empty bin is not taken for
    evidence. Returns the matplotlib figure.
    """
    import matplotlib.pyplot as plt

    rows = [r for r in rows if r["steps"] > 0]
    fig, (ax, ax_n) = plt.subplots(
        2, 1, figsize=(5.0, 5.6), sharex=True, gridspec_kw={"height_ratios": [3, 1]}
    )
    ax.plot([0, 1], [0, 1], "--", color="0.5", lw=1, label="calibrated")
    if rows:
        conf = np.array([r["mean_confidence"] for r in rows])
        share = np.array([r["localised_share"] for r in rows])
        steps = np.array([r["steps"] for r in rows])
        # 95 % Wilson interval of each bin's share: small bins are not over-read.
        z = 1.96
        centre = (share + z**2 / (2 * steps)) / (1 + z**2 / steps)
        half = z * np.sqrt(share * (1 - share) / steps + z**2 / (4 * steps**2)) / (1 + z**2 / steps)
        ax.errorbar(
            conf,
            share,
            yerr=[share - (centre - half), centre + half - share],
            fmt="o-",
            capsize=3,
            label="AMCL (95 % interval)",
        )
        lo = np.array([r["lo"] for r in rows])
        hi = np.array([r["hi"] for r in rows])
        ax_n.bar((lo + hi) / 2, steps / steps.sum(), width=(hi - lo) * 0.9, color="C0", alpha=0.6)
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.02)
    ax.set_ylabel(f"share of steps localised (< {localised_m:g} m)")
    ax.set_title(title or "Reliability of the localisation confidence")
    ax.legend(loc="upper left")
    ax.grid(alpha=0.3)
    ax_n.set_xlabel("localisation confidence")
    ax_n.set_ylabel("share of steps")
    ax_n.grid(alpha=0.3)
    fig.tight_layout()
    return fig
