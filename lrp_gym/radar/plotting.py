"""Range-Doppler map figure with detections and the true LRP distances."""

from __future__ import annotations

import numpy as np

from lrp_gym.radar.detections import Detections


def plot_range_doppler(
    map_db: np.ndarray,
    range_axis_m: np.ndarray,
    velocity_axis_mps: np.ndarray,
    detections: Detections,
    true_distances_m: np.ndarray | None = None,
    title: str = "range-Doppler map",
):
    """A matplotlib figure of the map (dBm), detections (circles) and LRP distances (lines)."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    dv = velocity_axis_mps[1] - velocity_axis_mps[0]
    dr = range_axis_m[1] - range_axis_m[0]
    top = float(np.max(map_db))
    im = ax.imshow(
        map_db,
        origin="lower",
        aspect="auto",
        cmap="viridis",
        vmin=top - 90,
        vmax=top,
        extent=(
            velocity_axis_mps[0] - dv / 2,
            velocity_axis_mps[-1] + dv / 2,
            range_axis_m[0] - dr / 2,
            range_axis_m[-1] + dr / 2,
        ),
    )
    fig.colorbar(im, ax=ax, label="power at antenna [dBm]")
    if len(detections):
        ax.scatter(
            detections.velocity_mps,
            detections.range_m,
            s=40,
            facecolors="none",
            edgecolors="red",
            label="detections",
        )
    if true_distances_m is not None:
        for i, d in enumerate(np.asarray(true_distances_m)):
            ax.axhline(
                d, color="white", ls="--", lw=0.8, label="true LRP distance" if i == 0 else None
            )
    # zoom on the room: everything of interest lies within the farthest detection or LRP
    far = max(
        [float(np.max(detections.range_m)) if len(detections) else 0.0]
        + ([float(np.max(true_distances_m))] if true_distances_m is not None else [])
    )
    if far > 0:
        ax.set_ylim(0.0, min(range_axis_m[-1] + dr / 2, 1.2 * far + 0.5))
    ax.set_xlabel("radial velocity [m/s]")
    ax.set_ylabel("range [m]")
    ax.set_title(title)
    ax.legend(loc="upper right", fontsize=8)
    return fig
