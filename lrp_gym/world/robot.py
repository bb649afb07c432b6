"""Differential-drive kinematics and odometry with noise on turned angle and travelled distance."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def wrap_angle(angle_rad: np.ndarray | float) -> np.ndarray | float:
    """Wrap angles to [-pi, pi)."""
    return (np.asarray(angle_rad) + np.pi) % (2.0 * np.pi) - np.pi


def integrate_unicycle(
    pose: np.ndarray,
    speed_mps: np.ndarray | float,
    turn_rate_rps: np.ndarray | float,
    dt_s: np.ndarray | float,
) -> np.ndarray:
    """Exact constant-(v, omega) motion over ``dt_s``: arcs, straight lines when omega = 0.

    Parameters
    ----------
    pose : array (..., 3)
        (x, y, theta) in metres and radians.
    speed_mps, turn_rate_rps : float or array (...)
        Forward speed and turn rate, held constant during ``dt_s``.
    dt_s : float or array (...)
        Duration; an array gives the poses after each of several durations (sub-steps).
    """
    pose = np.asarray(pose, dtype=float)
    x, y, th = pose[..., 0], pose[..., 1], pose[..., 2]
    v = np.asarray(speed_mps, dtype=float)
    w = np.asarray(turn_rate_rps, dtype=float)
    dth = w * dt_s
    small = np.abs(dth) < 1e-9
    # sin(th + dth) - sin(th) = 2 cos(th + dth/2) sin(dth/2); chord form avoids 0/0.
    chord = np.where(small, v * dt_s, 2.0 * v / np.where(small, 1.0, w) * np.sin(dth / 2.0))
    mid = th + dth / 2.0
    return np.stack(
        [x + chord * np.cos(mid), y + chord * np.sin(mid), wrap_angle(th + dth)], axis=-1
    )


def odometry_delta(prev_pose: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """Relative motion between two poses as (rot1, trans, rot2).

    The decomposition of Thrun et al.'s odometry motion model: turn by rot1 towards the new
    position, drive ``trans`` metres, turn by rot2 to the new heading.
    """
    prev_pose = np.asarray(prev_pose, dtype=float)
    pose = np.asarray(pose, dtype=float)
    dx, dy = pose[..., 0] - prev_pose[..., 0], pose[..., 1] - prev_pose[..., 1]
    trans = np.hypot(dx, dy)
    # Below a millimetre the direction of travel is noise: attribute the turn to rot2.
    heading = np.where(trans > 1e-3, np.arctan2(dy, dx), prev_pose[..., 2])
    rot1 = wrap_angle(heading - prev_pose[..., 2])
    rot2 = wrap_angle(pose[..., 2] - prev_pose[..., 2] - rot1)
    return np.stack([rot1, trans, rot2], axis=-1)


@dataclass(frozen=True)
class OdometryNoise:
    """Zero-mean Gaussian noise on the (rot1, trans, rot2) odometry decomposition.

    Two forms, summed:

    - fixed standard deviations (the paper's model): ``sigma_turn_rad`` on each turned angle,
      ``sigma_distance_m`` on the travelled distance;
    - AMCL-style ``alphas`` (a1..a4) in standard-deviation form: the std of a turn is
      ``a1 |turn| + a2 |trans|``, of the distance ``a3 |trans| + a4 (|rot1| + |rot2|)``.
    """

    sigma_turn_rad: float
    sigma_distance_m: float
    alphas: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0)  # a1..a4

    def std(self, delta: np.ndarray) -> np.ndarray:
        """Standard deviations (..., 3) of (rot1, trans, rot2) for odometry deltas (..., 3)."""
        a1, a2, a3, a4 = self.alphas
        r1, tr, r2 = np.abs(delta[..., 0]), np.abs(delta[..., 1]), np.abs(delta[..., 2])
        s_r1 = self.sigma_turn_rad + a1 * r1 + a2 * tr
        s_tr = self.sigma_distance_m + a3 * tr + a4 * (r1 + r2)
        s_r2 = self.sigma_turn_rad + a1 * r2 + a2 * tr
        return np.stack([s_r1, s_tr, s_r2], axis=-1)

    def sample(self, delta: np.ndarray, size: int | tuple, rng: np.random.Generator) -> np.ndarray:
        """Noisy copies of one delta (3,): array of shape ``size + (3,)``."""
        delta = np.asarray(delta, dtype=float)
        size = (int(size),) if isinstance(size, (int, np.integer)) else tuple(size)
        return delta + rng.standard_normal(size + (3,)) * self.std(delta)


def noisy_odometry(
    noise: OdometryNoise,
    prev_pose: np.ndarray | None,
    pose: np.ndarray,
    rng: np.random.Generator,
) -> np.ndarray:
    """What the wheel odometry reports for the move from ``prev_pose`` to ``pose``.

    The true ``(rot1, trans, rot2)`` plus one draw of ``noise`` from ``rng``. ``prev_pose``
    None is the first frame of a run: nothing moved yet, zeros, and no draw (so the random
    stream does not depend on whether a run starts with a move).
    """
    if prev_pose is None:
        return np.zeros(3)
    return noise.sample(odometry_delta(prev_pose, pose), (), rng)


def apply_odometry(poses: np.ndarray, deltas: np.ndarray) -> np.ndarray:
    """Move poses (..., 3) by odometry deltas (..., 3) = (rot1, trans, rot2)."""
    th = poses[..., 2] + deltas[..., 0]
    x = poses[..., 0] + deltas[..., 1] * np.cos(th)
    y = poses[..., 1] + deltas[..., 1] * np.sin(th)
    return np.stack([x, y, wrap_angle(th + deltas[..., 2])], axis=-1)


@dataclass(frozen=True)
class DiffDriveLimits:
    """Limits of the differential-drive robot.

    Attributes
    ----------
    max_speed_mps : float
        Largest forward speed; reverse is limited to ``max_reverse_mps``.
    max_turn_rate_rps : float
        Largest turn rate magnitude.
    radius_m : float
        Footprint radius used for collision checks.
    """

    max_speed_mps: float
    max_reverse_mps: float
    max_turn_rate_rps: float
    radius_m: float
