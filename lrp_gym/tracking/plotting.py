"""Figure of a tracking run: true, detected and tracked distances per reflector over the drive."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from lrp_gym.experiments.track_path import TrackRun


def plot_track_run(
    run: TrackRun, type_names: tuple[str, ...], type_index: np.ndarray, title: str = ""
):
    """True distances (lines), every detection (grey) and the reported distances.

    One panel per reflector type. A reported distance is drawn filled when it was measured in
    that frame and hollow when the track coasted or was not yet confirmed; it is coloured by
    the reflector it is closest to, so a track that follows a room return stands out as a
    marker off every line.
    """
    import matplotlib.pyplot as plt

    n_types = len(type_names)
    fig, axes = plt.subplots(1, n_types, figsize=(6.5 * n_types, 4), squeeze=False)
    frames = range(len(run.trajectory))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for t, ax in enumerate(axes[0]):
        refl = np.flatnonzero(type_index == t)
        for det_k, k in zip(run.detections, frames, strict=True):
            r = det_k.range_m
            ax.plot(np.full(len(r), k), r, ".", color="0.8", ms=3, zorder=1)
        for j, m in enumerate(refl):
            ax.plot(
                frames,
                run.truth_m[:, m],
                "-",
                color=colors[j % len(colors)],
                lw=1.2,
                label=f"reflector {m} (true)",
                zorder=2,
            )
        for k, fp in enumerate(run.fingerprints):
            d, fresh = fp.distances_m[t], fp.fresh[t]
            if len(d) == 0:
                continue
            nearest = np.argmin(np.abs(d[:, None] - run.truth_m[k, refl][None, :]), axis=1)
            for dist, f, j in zip(d, fresh, nearest, strict=True):
                c = colors[j % len(colors)]
                ax.plot(k, dist, "o", ms=6, mfc=c if f else "none", mec=c, zorder=3)
        ax.plot([], [], ".", color="0.8", label="detections (all)")
        ax.plot([], [], "o", color="0.3", label="tracked (hollow: coasting / tentative)")
        ax.set_ylim(0.0, float(np.nanmax(run.truth_m)) + 2.0)
        ax.set_xlabel("frame")
        ax.set_ylabel("distance [m]")
        ax.set_title(f"type {type_names[t]}" + (f" - {title}" if title else ""))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    return fig
