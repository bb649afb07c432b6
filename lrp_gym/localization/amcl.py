"""Adaptive Monte Carlo localisation over (x, y, theta) from unordered LRP distances.

One :meth:`Amcl.update` per radar frame:

1. *predict*: every particle moves by the odometry (rot1, trans, rot2) with its own sampled
   noise (:mod:`~lrp_gym.localization.particle_motion`); particles that leave the free space (room and
   obstacles grown by the robot radius) get weight zero;
2. *weight*: multiply by the likelihood of the fingerprint (:mod:`~lrp_gym.localization.likelihood`);
3. *estimate*: the paper's best-k rule or the heaviest cluster
   (:mod:`~lrp_gym.localization.particle_statistics`), with a 3x3 covariance about the estimate;
4. *resample* when the effective sample size falls below ``resample_ess_ratio * N``:
   low-variance resampling to a KLD-sampling particle count, with a share of uniformly drawn
   particles given by the ``alpha_slow`` / ``alpha_fast`` averages of the measurement
   likelihood (Augmented MCL, Thrun et al., ch. 8.3.5); the KLD count is computed vectorised
   rather than incrementally (:mod:`~lrp_gym.localization.kld`).

If every particle ends with weight zero (all left the free space, or the likelihood underflowed
with ``clutter_probability = 0``), the filter re-initialises uniformly, rather than crash.
"""

from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np

from lrp_gym.config import LocalizationConfig
from lrp_gym.localization.frame_evidence import FrameEvidence
from lrp_gym.localization.kld import KldBinner, augmented_particle_count
from lrp_gym.localization.likelihood import FingerprintModel, frame_fit
from lrp_gym.localization.particle_motion import (
    odometry_noise,
    particle_velocities,
    sample_motion,
    uniform_free_particles,
)
from lrp_gym.localization.particle_statistics import cluster_labels
from lrp_gym.localization.pose_estimate import PoseEstimate, cloud_estimate
from lrp_gym.localization.proposal import LostTest, MeasurementGrid, lost_test_model
from lrp_gym.localization.resampling import (
    effective_sample_size,
    mode_preserving_resample,
    systematic_resample,
)
from lrp_gym.localization.slip import slip_monitor
from lrp_gym.localization.visibility import RadarLink
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.world import World

#: Particles on which the recovery's measurement fit is evaluated (a strided subsample).
_FIT_SAMPLE = 256
#: Bins lighter than this share of the weight belong to no mode when resampling.
_MODE_BIN_MASS = 1e-5


class Amcl:
    """Particle filter localisation with KLD-adaptive particle count.

    Parameters
    ----------
    world : World
        Room (free space), reflector layout, radar height and maximum range, robot radius.
    cfg : LocalizationConfig
        Particle counts, noise, likelihood, KLD, recovery and estimator settings.
    link : RadarLink, optional
        The radar's link budget: the model predicts each reflector's detection from its SNR.

    Attributes
    ----------
    particles : ndarray (N, 3)
        Current particles (x_m, y_m, theta_rad).
    weights : ndarray (N,)
        Their normalised weights.
    """

    def __init__(
        self, world: World, cfg: LocalizationConfig, link: RadarLink | None = None
    ) -> None:
        self.world = world
        self.cfg = cfg
        self.model = FingerprintModel.for_world(world, cfg, link)  # the stack may swap it
        self.motion_noise = odometry_noise(cfg)
        self.slip = slip_monitor(self.motion_noise, cfg)
        self.clearance_m = float(world.robot.radius_m)
        self._size_xy = np.asarray(world.room.size_m[:2], dtype=float)
        self._simple_room = not world.room.obstacles
        self.binner = KldBinner(self._size_xy, cfg.kld_bin_m, np.deg2rad(cfg.kld_bin_deg))
        # Map-wide likelihood grids: a fine one for the global start, a coarse one per frame
        # for the lost test and recovery proposals (see lrp_gym.localization.proposal).
        self.global_proposal = cfg.global_proposal
        if self.global_proposal:
            self.grid = MeasurementGrid(self._size_xy, cfg.global_grid_m, self._free)
            self.start_grid = MeasurementGrid(
                self._size_xy, cfg.start_cell_m, self._free, max_cells=160_000
            )
        self.lost = self._new_lost_test()
        self.evidence = FrameEvidence(cfg.likelihood_exponent, cfg.likelihood_correlation_m)
        self._grid_loglik: np.ndarray | None = None
        self._grid_frame: Fingerprint | None = None  # the frame of the lost test's grid
        self._settled = False
        self._pending_global = False
        self.particles = np.zeros((0, 3))
        self.weights = np.zeros(0)
        self.w_slow = self.w_fast = self.p_random = 0.0
        self.n_injected = 0
        self._n_fits = 0
        self._predicted: tuple[np.ndarray, np.ndarray] | None = None
        self.last_k_bins = 0

    def spawn(self) -> Amcl:
        """Another robot's filter: the model, grids and binner shared, its own particles,
        weights and lost test (call :meth:`reset` before use)."""
        new = copy.copy(self)
        new.lost, new.evidence = self._new_lost_test(), copy.copy(self.evidence)
        new.slip = slip_monitor(self.motion_noise, self.cfg)
        new.particles, new.weights = np.zeros((0, 3)), np.zeros(0)
        new._predicted = new._grid_loglik = new._grid_frame = None
        return new

    @property
    def lost_model(self) -> FingerprintModel:
        """The model the lost test weighs with: the current one at its own outlier class and
        range std."""
        cell_xy_m = self.grid.cell_xy_m if self.global_proposal else None
        return lost_test_model(self.model, self.cfg, cell_xy_m)

    def _new_lost_test(self) -> LostTest:
        return LostTest.from_config(self.cfg, self.grid if self.global_proposal else None)

    # ------------------------------------------------------------------ sampling
    def _free(self, xy: np.ndarray) -> np.ndarray:
        """Whether floor positions (N, 2) are free for the robot (pass ``particles[:, :2]``)."""
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
        return uniform_free_particles(n, rng, self._size_xy, self._free, self.clearance_m)

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
        self.w_slow = self.w_fast = self.p_random = 0.0
        self.n_injected = 0
        self._n_fits = 0  # fits averaged since reset: the first one sets both averages
        self._predicted = None
        self.lost.reset()
        self.evidence.reset()
        if self.slip is not None:
            self.slip.reset()
        self._grid_loglik, self._grid_frame, self._settled = None, None, False
        # A uniform prior is drawn from the first frame's likelihood (sensor-based start).
        self._pending_global = bool(
            self.global_proposal and self.cfg.init == "uniform" and pose is None
        )

    # ------------------------------------------------------------------ update
    def update(
        self,
        odometry: np.ndarray,
        fingerprint: Fingerprint | None,
        rng: np.random.Generator,
        *,
        recovery: bool = True,
        speed_mps: float | None = None,
    ) -> PoseEstimate:
        """Predict with ``odometry`` (rot1, trans, rot2), weight with ``fingerprint`` (None =
        predict only), estimate, and resample if the effective sample size is low.

        ``speed_mps``, the robot's signed forward speed at this frame (wheel odometry), gives
        every particle a velocity along its heading, so that the fingerprint's Doppler weighs
        the heading (see :mod:`~lrp_gym.localization.likelihood`); None leaves it out.

        With ``recovery=False`` the fit statistic of augmented MCL is not taken from
        ``fingerprint``; the caller passes another one to :meth:`update_recovery` (scored on
        the same predicted cloud) before the next update.
        """
        if len(self.particles) == 0:
            raise RuntimeError("call reset() before update()")
        cfg = self.cfg
        noise = self.motion_noise if self.slip is None else self.slip.noise()
        self.particles = sample_motion(self.particles, odometry, noise, rng)
        self.lost.move(odometry[1])
        self.evidence.move(odometry[1])
        w = self.weights * self._free(self.particles[:, :2])
        self._predicted = (self.particles, w)  # references: weighting makes new arrays
        if fingerprint is not None and fingerprint.count > 0:
            w = self._weigh(fingerprint, w, rng, recovery, speed_mps)
        total = float(np.sum(w))
        if not (total > 0.0 and np.isfinite(total)):
            self.particles = self.uniform_particles(len(self.particles), rng)
            w = np.ones(len(self.particles))
            total = float(len(self.particles))
        self.weights = w / total
        ess = effective_sample_size(self.weights)
        estimate = self._estimate(ess)
        self._settled = estimate.settled
        if self.slip is not None:
            self.slip.update(odometry, estimate.pose, estimate.settled)
        n = len(self.weights)
        self.n_injected = 0
        # The lost test asks for recovery particles too, once past its threshold.
        p_lost_excess = max(0.0, 2.0 * self.lost.p_lost - 1.0)
        self.p_random = max(self.p_random, cfg.max_random_fraction * p_lost_excess)
        # Recovery needs a resampling step to inject: force one when it would add a particle.
        if ess < cfg.resample_ess_ratio * n or self.p_random * n >= 1.0:
            self._resample(rng)
        return replace(estimate, n_particles=len(self.particles))

    def _weigh(
        self,
        fingerprint: Fingerprint,
        w: np.ndarray,
        rng: np.random.Generator,
        recovery: bool,
        speed_mps: float | None,
    ) -> np.ndarray:
        """The lost test, then the predicted particles' weights ``w`` times the likelihood of
        ``fingerprint`` (or the importance weights of a global start)."""
        # The map's returns at the particles, once for the lost test and the weighting.
        vel = particle_velocities(self.particles, speed_mps)
        xy = self.particles[:, :2]
        returns = None if self._pending_global else self.model.map_returns_at(xy, fingerprint, vel)
        # The grid: lazily for recovery (at a global start only an injection uses it).
        self._grid_loglik, self._grid_frame = None, fingerprint
        if self.global_proposal and not self._pending_global:
            # lost_test_every > 1: the test (and its grid) may skip quiet frames
            marginal = self._cloud_marginal(fingerprint, w, returns)
            quiet = self._settled and self.p_random == 0.0
            if self.lost.due(quiet, marginal, fingerprint.count):
                grid = self._grid_loglik = self.grid.log_likelihood(self.lost_model, fingerprint)
                best = float(np.max(grid))
                xy = self.particles[:, :2]
                self.lost.update_marginal(
                    best, marginal, fingerprint.count, grid, xy, w, self.evidence.independence()
                )
                self._pending_global = self.lost.evidence_nats >= self.cfg.lost_restart_nats
        if self._pending_global:
            return self._global_start(fingerprint, rng, speed_mps)
        if recovery:
            self._update_recovery(self.particles, w, fingerprint)
        return w * self._likelihood(fingerprint, w, vel, returns)

    def _likelihood(
        self, fingerprint: Fingerprint, weights: np.ndarray, vel, returns
    ) -> np.ndarray:
        """Measurement likelihood (N,) of the particles, scaled so the best live one is 1
        (``vel`` from :func:`particle_velocities`, ``returns`` from
        :meth:`FingerprintModel.map_returns_at` at the particles, or None)."""
        ranges, rates = (None, None) if returns is None else returns
        loglik = self.model.log_likelihood(
            self.particles, fingerprint, velocity_xy=vel, map_ranges=ranges, map_rates=rates
        )
        # Tempering: the frames' errors are correlated (multipath persists while the robot
        # moves a few cm), so a product over frames would count the same evidence repeatedly.
        loglik *= self.evidence.take()
        shift = float(np.max(np.where(weights > 0.0, loglik, -np.inf)))
        if not np.isfinite(shift):
            shift = 0.0
        return np.exp(loglik - shift)

    def _global_start(
        self, fingerprint: Fingerprint, rng: np.random.Generator, speed_mps: float | None
    ) -> np.ndarray:
        """Replace the particles by a draw from the uniform prior times this frame's
        likelihood: positions from the fine grid, headings uniform; returns their importance
        weights ``L(x) / L(cell)`` (the Doppler term, if any, weighs the headings)."""
        self._pending_global = False
        self.lost.reset()
        n = len(self.particles)
        cell_ll = self.start_grid.log_likelihood(self.model, fingerprint)
        exponent = self.evidence.restart()  # a new cloud: this frame is its first evidence
        xy, cells = self.start_grid.draw(cell_ll * exponent, n, rng)
        self.particles = np.column_stack([xy, rng.uniform(-np.pi, np.pi, n)])
        loglik = self.model.log_likelihood(
            self.particles, fingerprint, velocity_xy=particle_velocities(self.particles, speed_mps)
        )
        log_w = (loglik - cell_ll[cells]) * exponent
        return np.exp(log_w - np.max(log_w))

    def _cloud_marginal(
        self, fingerprint: Fingerprint, prior_weights: np.ndarray, returns
    ) -> float | None:
        """The lost test's marginal log-likelihood of the predicted cloud (heading-free, on a
        subsample; ``returns``, the map's returns at all the particles, are sliced)."""
        stride = max(1, len(prior_weights) // _FIT_SAMPLE)
        sub = self.particles[::stride, :2]
        ranges = None if returns is None else np.ascontiguousarray(returns[0][:, ::stride])
        cloud_ll = self.lost_model.log_likelihood(sub, fingerprint, map_ranges=ranges)
        return self.lost.marginal(cloud_ll, prior_weights[::stride])

    def update_recovery(self, fingerprint: Fingerprint) -> None:
        """Score the last update's predicted cloud on ``fingerprint`` (see ``recovery``)."""
        if self._predicted is None or fingerprint.count == 0:
            return
        self._update_recovery(*self._predicted, fingerprint)

    def _update_recovery(
        self, particles: np.ndarray, prior_weights: np.ndarray, fingerprint: Fingerprint
    ) -> None:
        """Augmented MCL's short- and long-term averages of the measurement fit.

        The averaged quantity is :meth:`FingerprintModel.distance_fits` of the predicted
        particles rather than their mean likelihood: the likelihood is a product over the
        measured distances, so its scale changes by orders of magnitude with the number of
        distances and with one clutter distance, which the averages would read as a kidnap.
        The fit is evaluated on a strided subsample of at most ``_FIT_SAMPLE`` particles
        (resampled sets are ordered by ancestor, so the stride is a systematic sample).
        """
        cfg = self.cfg
        stride = max(1, len(prior_weights) // _FIT_SAMPLE)
        fits = self.model.distance_fits(
            particles[::stride, :2], prior_weights[::stride], fingerprint
        )
        fit = frame_fit(fits)
        if fit is None:
            return
        # Running means until 1/k falls below alpha (bias-corrected averages): the first
        # fit initialises both, and the long-term one is not anchored to the low fits of a
        # uniform prior's first frames.
        self._n_fits += 1
        inv_k = 1.0 / self._n_fits
        self.w_slow += max(cfg.alpha_slow, inv_k) * (fit - self.w_slow)
        self.w_fast += max(cfg.alpha_fast, inv_k) * (fit - self.w_fast)
        ratio = self.w_fast / (cfg.recovery_fit_ratio * self.w_slow)
        self.p_random = min(max(1.0 - ratio, 0.0), cfg.max_random_fraction)

    def estimate(self) -> PoseEstimate:
        """The pose estimate of the current particles and weights (no update)."""
        return self._estimate(effective_sample_size(self.weights))

    def _estimate(self, ess: float) -> PoseEstimate:
        return cloud_estimate(
            self.particles, self.weights, self.cfg, self._size_xy, ess, self.lost.p_lost
        )

    def _injected(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """Recovery particles: drawn from the last frame's likelihood grid (sensor resetting)
        when there is one, else uniform; headings uniform."""
        if self._grid_loglik is None and self._grid_frame is not None and self.global_proposal:
            self._grid_loglik = self.grid.log_likelihood(self.lost_model, self._grid_frame)
        if self._grid_loglik is None:
            return self.uniform_particles(n, rng)
        xy, _ = self.grid.draw(self._grid_loglik, n, rng)
        return np.column_stack([xy, rng.uniform(-np.pi, np.pi, n)])

    def _resample(self, rng: np.random.Generator) -> None:
        n = len(self.weights)
        idx = systematic_resample(self.weights, n, rng)
        self.last_k_bins = self.binner.count(self.particles, idx)
        n_new = augmented_particle_count(self.cfg, self.last_k_bins, self.p_random)
        new_weights = np.full(n_new, 1.0 / n_new)
        if self.cfg.mode_min_particles > 0:
            labels, _ = cluster_labels(
                self.particles, self.weights, self.cfg.kld_bin_m, self._size_xy, _MODE_BIN_MASS
            )
            idx, new_weights = mode_preserving_resample(
                self.weights, labels, n_new, self.cfg.mode_min_particles, rng
            )
        elif n_new != n:
            idx = systematic_resample(self.weights, n_new, rng)
        new = np.take(self.particles, idx, axis=0)
        n_random = int(rng.binomial(n_new, self.p_random)) if self.p_random > 0.0 else 0
        if n_random:
            injected = rng.choice(n_new, n_random, replace=False)
            new[injected] = self._injected(n_random, rng)
            new_weights[injected] = 1.0 / n_new  # a fresh array from either resampler
            new_weights /= new_weights.sum()
        self.n_injected = n_random
        self.particles = new
        self.weights = new_weights
