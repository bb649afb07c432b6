"""The Kalman equations of the distance tracker, over every track at once.

State ``x`` (n, 2) = (distance_m, rate_mps) and covariance ``P`` (n, 2, 2) of n tracks stacked,
so one call serves all tracks of a frame (and, later, all envs of a batch). The measurement is
the state itself (``H = I``: a detection's range and radial velocity). The equations are
filterpy's ``KalmanFilter.predict`` / ``update`` written for stacked arrays; the tests check
them against filterpy on the same inputs.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from filterpy.common import Q_discrete_white_noise


@lru_cache(maxsize=64)
def constant_velocity_model(dt_s: float, accel_std_mps2: float) -> tuple[np.ndarray, np.ndarray]:
    """Transition ``F`` and process noise ``Q`` (white acceleration) over ``dt_s``; cached, so
    treat them as read-only."""
    F = np.array([[1.0, dt_s], [0.0, 1.0]])
    return F, Q_discrete_white_noise(2, dt=dt_s, var=accel_std_mps2**2)


def kalman_predict(
    x: np.ndarray, P: np.ndarray, F: np.ndarray, Q: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Linear prediction ``x' = F x``, ``P' = F P F^T + Q`` of each stacked state."""
    return x @ F.T, F @ P @ F.T + Q


def kalman_update(
    x: np.ndarray, P: np.ndarray, z: np.ndarray, R: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Update each state ``x[i]`` with its measurement ``z[i]`` (n, 2), noise ``R`` (2, 2).

    ``H = I``; the covariance in Joseph form ``(I - K) P (I - K)^T + K R K^T``, which stays
    symmetric and positive definite in floating point (filterpy's ``update`` uses it too).
    """
    K = P @ np.linalg.inv(P + R)
    x = x + np.einsum("mij,mj->mi", K, z - x)
    I_K = np.eye(2) - K
    return x, I_K @ P @ I_K.transpose(0, 2, 1) + K @ R @ K.transpose(0, 2, 1)
