"""Pose estimates passed from positioning to the environment."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PoseEstimate:
    """A pose estimate with its uncertainty.

    Attributes
    ----------
    pose : ndarray, shape (3,)
        (x_m, y_m, theta_rad).
    covariance : ndarray, shape (3, 3)
        Covariance of (x, y, theta); heading variance from the circular spread.
    n_particles : int
        Particle count after this update (0 for the look-up table).
    ess : float
        Effective sample size before resampling (0 for the look-up table).
    converged : bool
        Whether the localiser vouches for the estimate: its confidence reaches the configured
        mass and the mode is tighter than the configured spread.
    confidence : float
        Probability in [0, 1] that the estimate is right (for AMCL: the posterior mass of the
        estimate's mode, discounted by the probability that the particles have lost the robot).
    n_modes : int
        Number of distinct posterior modes holding at least 5 % of the mass (0 if unknown).
    """

    pose: np.ndarray
    covariance: np.ndarray
    n_particles: int = 0
    ess: float = 0.0
    converged: bool = False
    confidence: float = 0.0
    n_modes: int = 0

    @property
    def position_std_m(self) -> float:
        """Root of the trace of the position covariance."""
        return float(np.sqrt(max(self.covariance[0, 0] + self.covariance[1, 1], 0.0)))

    @property
    def std(self) -> np.ndarray:
        """Standard deviations of (x, y, theta)."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))
