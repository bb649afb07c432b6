"""Pose estimates passed from positioning to the environment."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lrp_gym.config import LocalizationConfig
from lrp_gym.localization.particle_statistics import (
    best_k_mean,
    circular_mean,
    clusters,
    pose_covariance,
)


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
        Whether the localiser vouches for the estimate: its confidence reaches
        ``converged_mass`` and the mode is tighter than ``converged_std_m``.
    confidence : float
        Probability in [0, 1] that the estimate is right (for AMCL: the posterior mass of the
        estimate's mode, discounted by the probability that the particles have lost the robot).
    n_modes : int
        Number of distinct posterior modes holding at least 5 % of the mass (0 if unknown).
    settled : bool
        The looser flag the localiser's own consumers act on (clutter map, reflector
        monitor, map-aided tracking, slip, lost test): confidence at least ``settled_mass``,
        the same spread.
    """

    pose: np.ndarray
    covariance: np.ndarray
    n_particles: int = 0
    ess: float = 0.0
    converged: bool = False
    confidence: float = 0.0
    n_modes: int = 0
    settled: bool = False

    @property
    def position_std_m(self) -> float:
        """Root of the trace of the position covariance."""
        return float(np.sqrt(max(self.covariance[0, 0] + self.covariance[1, 1], 0.0)))

    @property
    def std(self) -> np.ndarray:
        """Standard deviations of (x, y, theta)."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))


#: A mode must hold this share of the posterior to count in ``PoseEstimate.n_modes``.
MODE_MASS = 0.05


def cloud_estimate(
    particles: np.ndarray,
    weights: np.ndarray,
    cfg: LocalizationConfig,
    size_xy_m: np.ndarray,
    ess: float,
    p_lost: float,
) -> PoseEstimate:
    """AMCL's pose estimate of a weighted particle cloud (``cfg.estimator``).

    The heaviest cluster's weighted mean (``cluster``) or the paper's best-k mean
    (``best_k``); the confidence is that cluster's mass discounted by ``p_lost``, the lost
    test's probability that the cloud has lost the robot.
    """
    sel, masses = clusters(particles, weights, cfg.kld_bin_m, size_xy_m)
    mass = float(masses[0]) if len(masses) else 0.0
    sub = particles[sel]
    w_sel = weights[sel]
    total = float(np.sum(w_sel))
    w_n = w_sel / total if total > 0.0 else np.full(len(sub), 1.0 / len(sub))
    mean_xy = w_n @ sub[:, :2]
    if cfg.estimator == "cluster":
        pose = np.array([mean_xy[0], mean_xy[1], circular_mean(sub[:, 2], w_n)])
    else:
        pose = best_k_mean(particles, weights, cfg.estimate_best_k, cfg.estimate_radius_m)
    cov = pose_covariance(particles, weights, pose)
    # Converged: one cluster holds (almost) all the weight and is tight about its own mean.
    # The spread of the whole set about the estimate would count the few particles that
    # the motion noise scatters away from the mode, and flicker while the error is ~1 cm.
    spread_m2 = max(float(w_n @ (sub[:, 0] ** 2 + sub[:, 1] ** 2) - mean_xy @ mean_xy), 0.0)
    confidence = mass * (1.0 - p_lost)
    converged, settled = convergence_flags(confidence, spread_m2, cfg)
    n_modes = int(np.count_nonzero(masses >= MODE_MASS))
    return PoseEstimate(
        pose, cov, len(particles), ess, converged, float(confidence), n_modes, settled
    )


def convergence_flags(
    confidence: float, spread_m2: float, cfg: LocalizationConfig
) -> tuple[bool, bool]:
    """(``converged``, ``settled``) of an estimate whose mode has ``confidence`` and position
    variance ``spread_m2`` (m^2): see :class:`PoseEstimate`."""
    tight = bool(np.sqrt(spread_m2) < cfg.converged_std_m)
    return (
        tight and confidence >= cfg.converged_mass,
        tight and confidence >= cfg.settled_mass,
    )
