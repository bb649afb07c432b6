"""Poses and velocities of a robot driving a waypoint path at constant speed, frame by frame."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Trajectory:
    """A sampled drive along a path (K frames).

    Attributes
    ----------
    times_s : ndarray, shape (K,)
        Frame times from the start of the path.
    poses : ndarray, shape (K, 3)
        ``(x_m, y_m, theta_rad)``; the heading points along the segment being driven.
    velocities_xy_mps : ndarray, shape (K, 2)
        Floor velocity of the robot at each frame.
    segment_index : ndarray of int, shape (K,)
        Index of the path segment driven at each frame (segment i runs from waypoint i to i+1).
    """

    times_s: np.ndarray
    poses: np.ndarray
    velocities_xy_mps: np.ndarray
    segment_index: np.ndarray

    def __len__(self) -> int:
        return len(self.times_s)


def path_trajectory(waypoints_m: np.ndarray, speed_mps: float, frame_period_s: float) -> Trajectory:
    """Drive a polyline at constant speed and sample it every ``frame_period_s``.

    The robot moves straight between waypoints and turns on the spot at each one (no time
    spent turning), as in the paper's path. A frame that falls on a waypoint belongs to the
    segment leaving it, so its heading and velocity already point along the next segment;
    the last frame (the end of the path, included when it falls on a frame time within
    1e-9 of the period) keeps the last segment's heading and velocity.

    Parameters
    ----------
    waypoints_m : array_like, shape (W, 2)
        At least two waypoints; repeated consecutive waypoints are dropped.
    speed_mps : float
        Constant floor speed (> 0).
    frame_period_s : float
        Time between frames (> 0).

    Returns
    -------
    Trajectory
    """
    wp = np.asarray(waypoints_m, dtype=float).reshape(-1, 2)
    if speed_mps <= 0 or frame_period_s <= 0:
        raise ValueError("speed_mps and frame_period_s must be positive")
    keep = np.ones(len(wp), dtype=bool)
    keep[1:] = np.linalg.norm(np.diff(wp, axis=0), axis=1) > 1e-12
    wp = wp[keep]
    if len(wp) < 2:
        raise ValueError("a path needs at least two distinct waypoints")
    seg = np.diff(wp, axis=0)
    seg_len = np.linalg.norm(seg, axis=1)
    unit = seg / seg_len[:, None]
    start_s = np.concatenate([[0.0], np.cumsum(seg_len)])
    total = start_s[-1]
    step = speed_mps * frame_period_s
    # Tolerance so that a frame meant to land on a waypoint is not lost to rounding.
    n_frames = int(np.floor(total / step + 1e-9)) + 1
    arc = np.minimum(np.arange(n_frames) * step, total)
    tol = 1e-9 * max(step, 1.0)
    index = np.clip(np.searchsorted(start_s, arc + tol, side="right") - 1, 0, len(seg) - 1)
    xy = wp[index] + unit[index] * (arc - start_s[index])[:, None]
    heading = np.arctan2(unit[index, 1], unit[index, 0])
    return Trajectory(
        times_s=np.arange(n_frames) * frame_period_s,
        poses=np.column_stack([xy, heading]),
        velocities_xy_mps=unit[index] * speed_mps,
        segment_index=index,
    )
