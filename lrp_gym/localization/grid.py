"""Histogram (grid) filter over (x, y, heading) with exactly AMCL's models: a Bayes yardstick.

The posterior is held on a regular grid: cells of ``grid_cell_m`` in x and y over the room and
``grid_cell_deg`` in heading (the paper room at the defaults: 100 x 100 x 72 cells). Cells
whose centre is outside the free space (room and obstacles grown by the robot radius) hold
zero. One :meth:`GridFilter.update` per radar frame:

1. *predict*: AMCL's odometry motion model as two convolutions
   (:mod:`~lrp_gym.localization.grid_motion`); mass that leaves the free space is dropped, as
   AMCL zeroes the particles that leave it;
2. *weight*: multiply every cell by the likelihood of the fingerprint at its centre, from the
   same :class:`~lrp_gym.localization.likelihood.FingerprintModel` as AMCL's;
3. *estimate*: the mean of the heaviest cluster of cells (AMCL's ``dominant_cluster`` on the
   cell centres, same bins and thresholds), or the paper's best-k rule on the cells, with the
   exact covariance of the grid about it; ``converged`` as AMCL defines it.

It is slow by design (no resampling, no adaptivity, every cell every frame) and draws no
random numbers: what it adds over AMCL is that no hypothesis is ever lost to sampling. If every
cell ends with zero mass it restarts from the uniform prior, as AMCL does.

For consumers of particle clouds (the tracker's :class:`~lrp_gym.tracking.prior.DistancePrior`,
rendering), :attr:`GridFilter.particles` and :attr:`GridFilter.weights` expose the cells with
non-negligible mass as weighted particles at the cell centres.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from scipy.special import ndtr

from lrp_gym.config import LocalizationConfig
from lrp_gym.localization.grid_motion import (
    convolve_heading,
    convolve_xy,
    heading_kernel,
    translation_kernels,
)
from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.localization.particle_motion import odometry_noise, wrap_fast
from lrp_gym.localization.particle_statistics import (
    best_k_mean,
    circular_variance_rad2,
    clusters,
)
from lrp_gym.localization.pose_estimate import PoseEstimate, convergence_flags
from lrp_gym.localization.visibility import RadarLink
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.world import World

#: Cells below this share of the uniform mass are negligible: together they hold < 0.1 %.
_NEGLIGIBLE = 1e-3
#: At most this many cells are exposed as particles (a systematic sample beyond).
_MAX_EXPOSED = 4096
#: Poses per call of the measurement model when it is evaluated on every (x, y, heading) cell.
_CHUNK = 1 << 16


class GridFilter:
    """Histogram filter with :class:`~lrp_gym.localization.amcl.Amcl`'s interface and models.

    Parameters
    ----------
    world : World
        Room (free space), reflector layout, radar height and maximum range, robot radius.
    cfg : LocalizationConfig
        Cell sizes (``grid_cell_m``, ``grid_cell_deg``), motion and measurement noise, prior
        (``init``, ``init_std``), estimator and convergence settings.

    Attributes
    ----------
    x_m, y_m : ndarray (nx,), (ny,)
        Cell centres in x and y.
    headings_rad : ndarray (H,)
        Cell centres in heading, ``-pi + k * 2 pi / H``.
    free : ndarray (nx, ny) of bool
        Cells whose centre is in the free space.
    """

    #: Whether :meth:`_log_likelihood` reads the heading column. While False, the model is
    #: evaluated once per free xy cell and broadcast over the headings (the headings passed
    #: are NaN, so a model that starts reading them fails loudly instead of silently).
    heading_dependent_likelihood: ClassVar[bool] = False

    def __init__(
        self, world: World, cfg: LocalizationConfig, link: RadarLink | None = None
    ) -> None:
        self.world = world
        self.cfg = cfg
        self.link = link
        self.model = FingerprintModel.for_world(world, cfg, link)
        self.motion_noise = odometry_noise(cfg)
        self.clearance_m = float(world.robot.radius_m)
        self._size_xy = np.asarray(world.room.size_m[:2], dtype=float)
        self.cell_m = float(cfg.grid_cell_m)
        nx, ny = np.maximum(np.ceil(self._size_xy / self.cell_m - 1e-9).astype(int), 1)
        self.x_m = (np.arange(nx) + 0.5) * self.cell_m
        self.y_m = (np.arange(ny) + 0.5) * self.cell_m
        n_h = max(int(round(360.0 / cfg.grid_cell_deg)), 1)
        self.cell_rad = 2.0 * np.pi / n_h
        self.headings_rad = -np.pi + np.arange(n_h) * self.cell_rad
        xy = np.stack(np.meshgrid(self.x_m, self.y_m, indexing="ij"), axis=-1)
        self.free = world.room.free(xy, self.clearance_m)
        if not self.free.any():
            raise ValueError("the room has no free grid cell for the robot")
        self._free_xy = xy[self.free]
        self._density = np.zeros((n_h, nx, ny))
        self._exposed: tuple[np.ndarray, np.ndarray, int] | None = None

    @property
    def shape(self) -> tuple[int, int, int]:
        """Grid shape (H, nx, ny)."""
        return self._density.shape

    @property
    def density(self) -> np.ndarray:
        """The posterior (H, nx, ny): cell probabilities summing to 1 (read-only view)."""
        view = self._density.view()
        view.flags.writeable = False
        return view

    def xy_marginal(self) -> np.ndarray:
        """Posterior probability of each xy cell (nx, ny), summed over headings."""
        return self._density.sum(axis=0)

    def spawn(self) -> GridFilter:
        """Another robot's filter (the grid filter is offline: a fresh one, nothing shared)."""
        return GridFilter(self.world, self.cfg, self.link)

    # ------------------------------------------------------------------ prior
    def reset(self, rng: np.random.Generator | None = None, pose: np.ndarray | None = None) -> None:
        """Start from the uniform prior, or from a Gaussian around ``pose``.

        As :meth:`Amcl.reset`: uniform over the free space and heading when
        ``cfg.init == "uniform"`` and ``pose`` is None; otherwise a Gaussian with ``init_std``
        about ``pose`` (or the room centre, heading 0). ``rng`` is not used (the interface's).
        """
        if self.cfg.init == "uniform" and pose is None:
            self._set_uniform()
            return
        mean = (
            np.asarray(pose, dtype=float)
            if pose is not None
            else np.array([*(self._size_xy / 2.0), 0.0])
        )
        std = np.maximum(np.asarray(self.cfg.init_std, dtype=float), 1e-12)
        # Cell probabilities of the Gaussian: differences of its CDF at the cell edges.
        px = _cell_probabilities(self.x_m - mean[0], self.cell_m, std[0])
        py = _cell_probabilities(self.y_m - mean[1], self.cell_m, std[1])
        # Wrapped normal in heading: the mass of the neighbouring turns too.
        rel = wrap_fast(self.headings_rad - mean[2])
        below, centre, above = (
            _cell_probabilities(rel + w * 2.0 * np.pi, self.cell_rad, std[2]) for w in (-1, 0, 1)
        )
        pth = below + centre + above
        d = pth[:, None, None] * (px[:, None] * py[None, :] * self.free)[None]
        total = float(d.sum())
        if not total > 0.0:  # the Gaussian misses the free space: AMCL would restart too
            self._set_uniform()
            return
        self._density = d / total
        self._exposed = None

    def _set_uniform(self) -> None:
        d = np.broadcast_to(self.free, self._density.shape).astype(float)
        self._density = d / d.sum()
        self._exposed = None

    # ------------------------------------------------------------------ update
    def update(
        self,
        odometry: np.ndarray,
        fingerprint: Fingerprint | None,
        rng: np.random.Generator | None = None,
        *,
        recovery: bool = True,
        speed_mps: float | None = None,
    ) -> PoseEstimate:
        """Predict with ``odometry`` (rot1, trans, rot2), weight with ``fingerprint`` (None =
        predict only) and estimate. ``rng`` and ``recovery`` are the interface's: the grid
        draws nothing and needs no recovery (no hypothesis is ever dropped)."""
        if not self._density.any():
            raise RuntimeError("call reset() before update()")
        if self.predict(odometry) > 0.0 and fingerprint is not None and fingerprint.count > 0:
            self._weigh(fingerprint)
        total = float(self._density.sum())
        if not (total > 0.0 and np.isfinite(total)):
            self._set_uniform()
        else:
            self._density /= total
        self._exposed = None
        return self.estimate()

    def update_recovery(self, fingerprint: Fingerprint) -> None:
        """No-op: the grid keeps every hypothesis, it has nothing to recover."""

    def predict(self, odometry: np.ndarray) -> float:
        """The motion update alone; returns the share of the mass that stayed in the free space.

        The posterior is renormalised (restarted uniform if nothing stayed, as AMCL does).
        """
        odometry = np.asarray(odometry, dtype=float)
        std = self.motion_noise.std(odometry)
        kernels, radius = translation_kernels(
            self.headings_rad, odometry, std, self.cell_m, self.cell_rad
        )
        d = convolve_xy(self._density, kernels, radius)
        d = convolve_heading(d, heading_kernel(len(self.headings_rad), odometry, std))
        d = d * self.free  # also a copy when both kernels were the identity
        kept = float(d.sum())
        self._exposed = None
        if not (kept > 0.0 and np.isfinite(kept)):
            self._set_uniform()
            return 0.0
        self._density = d / kept
        return kept

    def _weigh(self, fingerprint: Fingerprint) -> None:
        """Multiply every free cell by the fingerprint's likelihood at its centre."""
        n_h = len(self.headings_rad)
        if self.heading_dependent_likelihood:
            poses = np.concatenate(
                [
                    np.repeat(self._free_xy[None], n_h, axis=0),
                    np.broadcast_to(self.headings_rad[:, None, None], (n_h, len(self._free_xy), 1)),
                ],
                axis=2,
            ).reshape(-1, 3)
            loglik = np.concatenate(
                [
                    self._log_likelihood(poses[i : i + _CHUNK], fingerprint)
                    for i in range(0, len(poses), _CHUNK)
                ]
            ).reshape(n_h, -1)
        else:
            poses = np.column_stack([self._free_xy, np.full(len(self._free_xy), np.nan)])
            loglik = self._log_likelihood(poses, fingerprint)[None, :]
            if np.isnan(loglik).any():
                raise RuntimeError(
                    "the measurement model reads the heading: set heading_dependent_likelihood"
                )
        mass = self._density[:, self.free]  # (H, n_free)
        held = np.broadcast_to(loglik, mass.shape)[mass > 0.0]
        shift = float(held.max()) if held.size else 0.0
        self._density[:, self.free] = mass * np.exp(loglik - (shift if np.isfinite(shift) else 0))

    def _log_likelihood(self, poses: np.ndarray, fingerprint: Fingerprint) -> np.ndarray:
        """Log-likelihood (N,) of ``fingerprint`` at poses (N, 3): the one call of the model.

        The position-only part of AMCL's model, tempered as AMCL tempers it; the heading column
        is ignored (NaN unless :attr:`heading_dependent_likelihood`). AMCL's Doppler term is
        left out: on the full (x, y, heading) grid it costs 72 model calls per frame.
        """
        loglik = self.model.log_likelihood(poses[:, :2], fingerprint)
        return loglik * self.cfg.likelihood_exponent

    # ------------------------------------------------------------------ estimate
    def estimate(self) -> PoseEstimate:
        """The pose estimate of the current posterior (no update).

        The cells are AMCL's particles here: the heaviest cluster of
        :func:`~lrp_gym.localization.particle_statistics.dominant_cluster` (bins of ``kld_bin_m``)
        gives the estimate (``estimator: cluster``; its heading is the circular mean of the
        cluster's heading mass) and decides ``converged`` with AMCL's rule. ``best_k`` averages
        the heaviest xy cells near the heaviest one. ``n_particles`` counts the cells of
        non-negligible mass, ``ess`` is ``1 / sum p^2`` over the cells.
        """
        cfg = self.cfg
        d = self._density
        xy = self._free_xy
        w = d.sum(axis=0)[self.free]
        # Per xy cell, the resultant of its heading mass (for circular means).
        unit = np.stack([np.cos(self.headings_rad), np.sin(self.headings_rad)])
        c, s = (unit @ d.reshape(len(unit[0]), -1)).reshape(2, *self.free.shape)[:, self.free]
        sel, masses = clusters(xy, w, cfg.kld_bin_m, self._size_xy)
        mass = float(masses[0]) if len(masses) else 0.0
        w_sel = w[sel]
        total = float(w_sel.sum())
        w_n = w_sel / total if total > 0.0 else np.full(len(w_sel), 1.0 / len(w_sel))
        mean_xy = w_n @ xy[sel]
        if cfg.estimator == "cluster":
            pose = np.array([*mean_xy, np.arctan2(s[sel].sum(), c[sel].sum())])
        else:
            cells = np.column_stack([xy, np.arctan2(s, c)])
            pose = best_k_mean(cells, w, cfg.estimate_best_k, cfg.estimate_radius_m)
        # AMCL's spread of the cluster about its own mean, with the mass uniform in each cell.
        spread_m2 = max(float(w_n @ np.sum(xy[sel] ** 2, axis=1) - mean_xy @ mean_xy), 0.0)
        spread_m2 += self.cell_m**2 / 6.0
        converged, settled = convergence_flags(mass, spread_m2, cfg)
        ess = 1.0 / float(np.sum(d * d))
        n_modes = int(np.count_nonzero(masses >= 0.05))
        cov, n_cells = self._covariance(pose), self._exposure()[2]
        return PoseEstimate(pose, cov, n_cells, ess, converged, mass, n_modes, settled)

    def _covariance(self, pose: np.ndarray) -> np.ndarray:
        """Exact 3x3 covariance of the grid about ``pose`` (heading variance ``-2 ln R``), with
        the uniform spread within a cell (``size^2 / 12``) on the diagonal."""
        d = self._density
        marg = d.sum(axis=0)
        dx = self.x_m - pose[0]
        dy = self.y_m - pose[1]
        q = np.tensordot(wrap_fast(self.headings_rad - pose[2]), d, axes=1)  # (nx, ny)
        cov = np.empty((3, 3))
        cov[0, 0] = dx**2 @ marg.sum(axis=1) + self.cell_m**2 / 12.0
        cov[1, 1] = marg.sum(axis=0) @ dy**2 + self.cell_m**2 / 12.0
        cov[0, 1] = cov[1, 0] = dx @ marg @ dy
        cov[0, 2] = cov[2, 0] = dx @ q.sum(axis=1)
        cov[1, 2] = cov[2, 1] = q.sum(axis=0) @ dy
        cov[2, 2] = circular_variance_rad2(self.headings_rad, d.sum(axis=(1, 2)))
        cov[2, 2] += self.cell_rad**2 / 12.0
        return cov

    # ------------------------------------------------------------------ as particles
    @property
    def particles(self) -> np.ndarray:
        """Centres (K, 3) of the cells of non-negligible mass: (x_m, y_m, theta_rad).

        Beyond 4096 such cells, a systematic sample of them in cell order (every mode in
        proportion to its mass; a cell drawn more than once appears once, heavier).
        """
        return self._exposure()[0]

    @property
    def weights(self) -> np.ndarray:
        """Weights (K,) of :attr:`particles`, summing to 1."""
        return self._exposure()[1]

    def _exposure(self) -> tuple[np.ndarray, np.ndarray, int]:
        if self._exposed is None:
            flat = self._density.ravel()
            # Cells below this threshold hold less than _NEGLIGIBLE of the mass together.
            idx = np.flatnonzero(flat >= _NEGLIGIBLE / flat.size)
            n_significant = len(idx)
            w = flat[idx]
            if len(idx) > _MAX_EXPOSED:
                cdf = np.cumsum(w)
                picks = (np.arange(_MAX_EXPOSED) + 0.5) / _MAX_EXPOSED * cdf[-1]
                pos = np.minimum(np.searchsorted(cdf, picks), len(idx) - 1)
                pos, counts = np.unique(pos, return_counts=True)
                idx, w = idx[pos], counts.astype(float)
            k, i, j = np.unravel_index(idx, self._density.shape)
            particles = np.column_stack([self.x_m[i], self.y_m[j], self.headings_rad[k]])
            self._exposed = (particles, w / w.sum(), n_significant)
        return self._exposed


def _cell_probabilities(centres: np.ndarray, width: float, std: float) -> np.ndarray:
    """Probability of N(0, std^2) in the cells of ``width`` about ``centres``."""
    return ndtr((centres + width / 2.0) / std) - ndtr((centres - width / 2.0) / std)
