"""Figures of driven episodes: room, reflectors, waypoints, true and estimated paths."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from lrp_gym.output import save_figure


def trajectory_figure(
    world: Any, true_xy: np.ndarray, est_xy: np.ndarray, waypoints_m: np.ndarray, title: str = ""
):
    """A top view of one episode.

    Parameters
    ----------
    world : lrp_gym.world.World
        Room (walls, obstacles) and reflector layout.
    true_xy, est_xy : ndarray, shape (T, 2)
        True and estimated positions, one per frame.
    waypoints_m : ndarray, shape (K, 2)
        The task's waypoint path (last one is the goal).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from lrp_gym.world.plotting import draw_room

    lx, ly = world.room.size_m[:2]
    fig, ax = plt.subplots(figsize=(7.6, 6.0 * ly / lx + 0.4))
    draw_room(ax, world, marker_size=110)
    ax.plot(*waypoints_m.T, "o--", color="0.5", ms=4, lw=1, label="waypoints")
    goal_x, goal_y = waypoints_m[-1]
    ax.scatter(
        goal_x, goal_y, marker="*", s=250, color="gold", edgecolor="k", zorder=6, label="goal"
    )
    ax.plot(*true_xy.T, "-", color="tab:green", lw=2, label="true path")
    ax.plot(*est_xy.T, ".-", color="tab:purple", lw=1, ms=4, alpha=0.8, label="estimated path")
    ax.scatter(
        true_xy[0, 0],
        true_xy[0, 1],
        s=60,
        color="tab:green",
        edgecolor="k",
        zorder=7,
        label="start",
    )
    ax.set_xlim(-0.2, lx + 0.2)
    ax.set_ylim(-0.2, ly + 0.2)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, framealpha=0.9)
    if title:
        ax.set_title(title, fontsize=10)
    return fig


def save_trajectory(
    path: str | Path,
    world: Any,
    true_xy: np.ndarray,
    est_xy: np.ndarray,
    waypoints_m: np.ndarray,
    title: str = "",
) -> Path:
    """Write :func:`trajectory_figure` to ``path`` (atomically)."""
    return save_figure(trajectory_figure(world, true_xy, est_xy, waypoints_m, title), path)
