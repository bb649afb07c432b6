"""The figure of ``lrp-gym reproduce-paper --plot``: per-position errors against the paper's."""

from __future__ import annotations

from typing import cast

import numpy as np

from lrp_gym.experiments.reproduce import PAPER, Reproduction

FLOOR_M = 1e-3  # log axis: an exact hit is drawn at 1 mm


def plot_errors(result: Reproduction, title: str = ""):
    """Per-position errors on a log axis: ours (median, whiskers min..max over the runs) and
    the paper's published values (LUT failures, AMCL mean, AMCL convergence)."""
    import matplotlib.pyplot as plt

    pos = np.arange(1, result.lut_errors_m.shape[1] + 1)
    fig, ax = plt.subplots(figsize=(7.5, 4))
    _draw_our_errors(ax, result, pos)
    _draw_paper_values(ax)
    _style_error_axes(ax, pos, title)
    return fig


def _draw_our_errors(ax, result: Reproduction, pos: np.ndarray) -> None:
    """Each localiser's errors per position: median marker, whiskers from min to max run."""
    runs = len(result.amcl_errors_m)
    series = [
        (result.lut_errors_m, "s", "tab:orange", -0.12, "look-up table"),
        (result.amcl_errors_m, "o-", "tab:blue", 0.12, "AMCL"),
    ]
    if result.grid_errors_m is not None:
        series.append((result.grid_errors_m, "^--", "tab:green", 0.0, "grid filter"))
    for errors, fmt, color, dx, label in series:
        e = np.maximum(errors, FLOOR_M)
        mid, lo, hi = np.median(e, 0), e.min(0), e.max(0)
        ax.errorbar(
            pos + dx,
            mid,
            yerr=np.vstack([mid - lo, hi - mid]),
            fmt=fmt,
            color=color,
            capsize=3,
            ms=5,
            label=f"{label}: median, bars min–max ({runs} runs)",
        )


def _draw_paper_values(ax) -> None:
    """The paper's published figures: LUT failures, AMCL mean error, AMCL convergence."""
    fail = cast(dict[int, float], PAPER["lut_failures_m"])
    ax.plot(
        list(fail),
        list(fail.values()),
        "x",
        color="tab:red",
        ms=9,
        mew=2,
        label="paper: look-up table failures",
    )
    ax.axhline(
        cast(float, PAPER["amcl_mean_error_m"]),
        color="tab:blue",
        ls="--",
        lw=1,
        label=f"paper: AMCL mean error {PAPER['amcl_mean_error_m']} m",
    )
    ax.axvline(
        cast(float, PAPER["amcl_converged_after"]),
        color="grey",
        ls=":",
        lw=1,
        label=f"paper: AMCL converged at position {PAPER['amcl_converged_after']}",
    )


def _style_error_axes(ax, pos: np.ndarray, title: str) -> None:
    """Log error axis from just under the 1 mm floor, one tick per position, legend outside."""
    ax.set_yscale("log")
    ax.set_ylim(FLOOR_M * 0.8, None)
    ax.set_xlabel("position on the path")
    ax.set_ylabel("position error [m] (log scale)")
    ax.set_xticks(pos)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    if title:
        ax.set_title(title, fontsize=10)
