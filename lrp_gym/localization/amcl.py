"""Adaptive Monte Carlo localisation over (x, y, theta) from unordered LRP distances.

One :meth:`Amcl.update` per radar frame:

1. *predict*: every particle moves by the odometry (rot1, trans, rot2) with its own sampled
   noise (:mod:`~lrp_gym.localization.motion`); particles that leave the free space (room and
   obstacles grown by the robot radius) get weight zero;
2. *weight*: multiply by the likelihood of the fingerprint (:mod:`~lrp_gym.localization.likelihood`);
3. *estimate*: the paper's best-k rule or the heaviest cluster
   (:mod:`~lrp_gym.localization.estimators`), with a 3x3 covariance about the estimate;
4. *resample* when the effective sample size falls below ``resample_ess_ratio * N``:
   low-variance resampling to a KLD-sampling particle count, with a share of uniformly drawn
   particles given by the ``alpha_slow`` / ``alpha_fast`` averages of the measurement
   likelihood (Augmented MCL, Thrun et al., ch. 8.3.5).

The KLD count is computed vectorised rather than incrementally: the ``k`` occupied bins are
counted on a systematic resample of the current size ``N``, and the new size is
``n_chi(k)`` clamped to ``[min_particles, max_particles]``. Because ``k`` can only grow with
the sample size, this never asks for fewer particles than Fox's incremental rule on the same
draw would when the population shrinks; it adapts one resampling step later when it grows.

If every particle ends with weight zero (all left the free space, or the likelihood
underflowed with ``clutter_probability = 0``), the filter re-initialises uniformly: a global
relocalisation rather than a crash.
"""

from __future__ import annotations

import numpy as np

from lrp_gym.config import LocalizationConfig
from lrp_gym.localization.estimate import PoseEstimate
from lrp_gym.localization.estimators import best_k_mean, cluster_mean, pose_covariance
from lrp_gym.localization.kld import KldBinner, kld_particle_count
from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.localization.motion import sample_motion
from lrp_gym.localization.resampling import effective_sample_size, systematic_resample
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.robot import OdometryNoise
from lrp_gym.world.world import World


class Amcl:
    """Particle filter localisation with KLD-adaptive particle count.

    Parameters
    ----------
    world : World
        Room (free space), reflector layout, radar height and maximum range, robot radius.
    cfg : LocalizationConfig
        Particle counts, noise, likelihood, KLD, recovery and estimator settings.

    Attributes
    ----------
    particles : ndarray (N, 3)
        Current particles (x_m, y_m, theta_rad).
    weights : ndarray (N,)
        Their normalised weights.
    """

    def __init__(self, world: World, cfg: LocalizationConfig) -> None:
        self.world = world
        self.cfg = cfg
        self.model = FingerprintModel(
            world.layout,
            world.mount_height_m,
            cfg.measurement_std_m,
            cfg.clutter_probability,
            world.fmcw.max_range_m,
        )
        mn = cfg.motion_noise
        self.motion_noise = OdometryNoise(
            np.deg2rad(mn.sigma_turn_deg), mn.sigma_distance_m, tuple(mn.alphas)
        )
        self.clearance_m = float(world.robot.radius_m)
        self._size_xy = np.asarray(world.room.size_m[:2], dtype=float)
        self._simple_room = not world.room.obstacles
        self.binner = KldBinner(self._size_xy, cfg.kld_bin_m, np.deg2rad(cfg.kld_bin_deg))
        self.particles = np.zeros((0, 3))
        self.weights = np.zeros(0)
        self.w_slow = 0.0
        self.w_fast = 0.0
        self.last_k_bins = 0

    # ------------------------------------------------------------------ sampling
    def _free(self, xy: np.ndarray) -> np.ndarray:
        if self._simple_room:
            c = self.clearance_m
            return (
                (xy[:, 0] >= c)
                & (xy[:, 0] <= self._size_xy[0] - c)
                & (xy[:, 1] >= c)
                & (xy[:, 1] <= self._size_xy[1] - c)
            )
        return self.world.room.free(xy, self.clearance_m)

    def uniform_particles(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """``n`` particles uniform over the free space (rejection sampling), headings uniform."""
        out = np.empty((0, 2))
        for _ in range(1000):
            if len(out) >= n:
                break
            cand = rng.random((max(2 * (n - len(out)), 16), 2)) * self._size_xy
            out = np.concatenate([out, cand[self._free(cand)]])
        if len(out) < n:
            raise ValueError("the room has (almost) no free space for the robot")
        th = rng.uniform(-np.pi, np.pi, n)
        return np.column_stack([out[:n], th])

    def reset(self, rng: np.random.Generator, pose: np.ndarray | None = None) -> None:
        """Start from the uniform prior, or from a Gaussian around ``pose``.

        The uniform prior is used when ``cfg.init == "uniform"`` and ``pose`` is None; otherwise
        ``pose`` (or, if None, ``init_std`` around the room centre) is the Gaussian's mean.
        """
        n = self.cfg.initial_particles
        if self.cfg.init == "uniform" and pose is None:
            self.particles = self.uniform_particles(n, rng)
        else:
            mean = (
                np.asarray(pose, dtype=float)
                if pose is not None
                else np.array([*(self._size_xy / 2.0), 0.0])
            )
            p = mean + rng.standard_normal((n, 3)) * np.asarray(self.cfg.init_std)
            p[:, 2] = (p[:, 2] + np.pi) % (2.0 * np.pi) - np.pi
            self.particles = p
        self.weights = np.full(n, 1.0 / n)
        self.w_slow = 0.0
        self.w_fast = 0.0

    # ------------------------------------------------------------------ update
    def update(
        self, odometry: np.ndarray, fingerprint: Fingerprint | None, rng: np.random.Generator
    ) -> PoseEstimate:
        """Predict with ``odometry`` (rot1, trans, rot2), weight with ``fingerprint`` (None =
        predict only), estimate, and resample if the effective sample size is low."""
        if len(self.particles) == 0:
            raise RuntimeError("call reset() before update()")
        cfg = self.cfg
        self.particles = sample_motion(self.particles, odometry, self.motion_noise, rng)
        w = self.weights * self._free(self.particles)
        if fingerprint is not None and fingerprint.count > 0:
            loglik = self.model.log_likelihood(self.particles, fingerprint)
            shift = float(np.max(np.where(w > 0.0, loglik, -np.inf)))
            if not np.isfinite(shift):
                shift = 0.0
            w = w * np.exp(loglik - shift)
            total = float(np.sum(w))
            if total > 0.0 and np.isfinite(total):
                w_avg = total * np.exp(shift)  # weighted mean likelihood (weights summed to 1)
                self.w_slow += cfg.alpha_slow * (w_avg - self.w_slow)
                self.w_fast += cfg.alpha_fast * (w_avg - self.w_fast)
        total = float(np.sum(w))
        if not (total > 0.0 and np.isfinite(total)):
            self.particles = self.uniform_particles(len(self.particles), rng)
            w = np.ones(len(self.particles))
            total = float(len(self.particles))
        self.weights = w / total
        ess = effective_sample_size(self.weights)
        estimate = self._estimate(ess)
        if ess < cfg.resample_ess_ratio * len(self.weights):
            self._resample(rng)
        return PoseEstimate(
            estimate.pose, estimate.covariance, len(self.particles), ess, estimate.converged
        )

    def estimate(self) -> PoseEstimate:
        """The pose estimate of the current particles and weights (no update)."""
        return self._estimate(effective_sample_size(self.weights))

    def _estimate(self, ess: float) -> PoseEstimate:
        cfg = self.cfg
        if cfg.estimator == "cluster":
            pose = cluster_mean(self.particles, self.weights, cfg.kld_bin_m, self._size_xy)
        else:
            pose = best_k_mean(
                self.particles, self.weights, cfg.estimate_best_k, cfg.estimate_radius_m
            )
        cov = pose_covariance(self.particles, self.weights, pose)
        converged = bool(np.sqrt(max(cov[0, 0] + cov[1, 1], 0.0)) < cfg.converged_std_m)
        return PoseEstimate(pose, cov, len(self.particles), ess, converged)

    def _resample(self, rng: np.random.Generator) -> None:
        cfg = self.cfg
        n = len(self.weights)
        idx = systematic_resample(self.weights, n, rng)
        self.last_k_bins = self.binner.count(self.particles, idx)
        n_new = kld_particle_count(self.last_k_bins, cfg.kld_error, cfg.kld_quantile)
        n_new = int(np.clip(n_new, cfg.min_particles, cfg.max_particles))
        if n_new != n:
            idx = systematic_resample(self.weights, n_new, rng)
        new = np.take(self.particles, idx, axis=0)
        if self.w_slow > 0.0:
            p_random = max(0.0, 1.0 - self.w_fast / self.w_slow)
            n_random = int(rng.binomial(n_new, p_random)) if p_random > 0.0 else 0
            if n_random:
                new[rng.choice(n_new, n_random, replace=False)] = self.uniform_particles(
                    n_random, rng
                )
        self.particles = new
        self.weights = np.full(n_new, 1.0 / n_new)
