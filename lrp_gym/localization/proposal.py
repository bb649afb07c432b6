"""Where do the measurements alone put the robot? A map-wide likelihood grid for AMCL.

The measurement model depends on the position only (the Doppler term aside), so the likelihood
of one frame can be evaluated on a grid of floor positions covering the free space. AMCL uses
that grid twice:

- **Sensor-based proposals.** A uniform prior sampled blindly puts a handful of particles into
  each likelihood peak a few centimetres wide, so which mode wins the first resampling steps is
  sampling luck. Drawing positions in proportion to the likelihood on the grid (jittered within
  the cell, with importance weights that undo the proposal) represents every mode in proportion
  to its posterior mass: the same posterior, far fewer particles wasted. Recovery injects
  particles the same way instead of uniformly (Thrun et al., *Probabilistic Robotics*, 8.3.7,
  sensor resetting).
- **A lost test.** The log-likelihood of the best grid cell against the marginal likelihood of
  the predicted particle cloud is the per-frame evidence that the robot is somewhere the cloud
  is not. A CUSUM of it, less a drift for the grid's selection bias, accumulates that evidence
  over frames and resets while the cloud explains the data; its value gives the probability
  that the cloud has lost the robot. A second CUSUM weighs a filter over the same cells
  against the cloud (:mod:`~lrp_gym.localization.grid_alternative`): it pays the selection
  once, not in every frame, and so hears a wrong cloud that the truth beats by a few nats a
  frame.
"""

from __future__ import annotations

import copy
import weakref
from dataclasses import dataclass

import numpy as np

from lrp_gym.config import LocalizationConfig
from lrp_gym.localization.grid_alternative import GridAlternative
from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.tracking.fingerprint import Fingerprint

_CHUNK = 20_000
#: With ``every_frames > 1``, a frame may skip the test only if its deficit against the last
#: best cell is this far below the drift (the best cell itself moves a little between frames).
SKIP_MARGIN_NATS = 1.5


class MeasurementGrid:
    """Free floor positions on a regular grid and the frame likelihood on them.

    Parameters
    ----------
    size_xy_m : array (2,)
        Room extent.
    cell_m : float
        Grid spacing.
    free : callable
        ``free(xy) -> bool mask`` of positions the robot can occupy.
    max_cells : int
        Cell budget: ``cell_m`` grows in rooms that would need more cells.
    """

    def __init__(self, size_xy_m: np.ndarray, cell_m: float, free, max_cells: int = 40_000) -> None:
        # A large room gets coarser cells: the grid is evaluated on every frame.
        cell_m = max(cell_m, float(np.sqrt(np.prod(size_xy_m) / max_cells)))
        nx, ny = np.maximum(np.floor(np.asarray(size_xy_m) / cell_m).astype(int), 1)
        gx = (np.arange(nx) + 0.5) * (size_xy_m[0] / nx)
        gy = (np.arange(ny) + 0.5) * (size_xy_m[1] / ny)
        xy = np.stack(np.meshgrid(gx, gy, indexing="ij"), axis=-1).reshape(-1, 2)
        ij = np.stack(np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij"), axis=-1)
        self.cell_xy_m = np.array([size_xy_m[0] / nx, size_xy_m[1] / ny])
        is_free = free(xy)
        self.centres_m = xy[is_free]
        self.cell_index = ij.reshape(-1, 2)[is_free]  # (column, row) of each free cell
        self._free = free
        self._map_model: FingerprintModel | None = None
        self._map_ranges: list[np.ndarray | None] = []
        self._expected: list[list[np.ndarray]] = []
        self._p_detect: list[np.ndarray | None] = []

    def __len__(self) -> int:
        return len(self.centres_m)

    def log_likelihood(self, model: FingerprintModel, fingerprint: Fingerprint) -> np.ndarray:
        """Heading-free log-likelihood (C,) of the frame at every free cell centre (in chunks:
        the model's work arrays grow with detections x reflectors x positions)."""
        xy = self.centres_m
        chunks = range(0, len(xy), _CHUNK)
        if self._map_model is not model:
            # The cells do not move: the map's predicted returns, the reflectors' detection
            # probabilities and ranges there are computed once per model.
            self._map_model = model
            parts = [xy[i : i + _CHUNK] for i in chunks]
            self._map_ranges = [model.map_return_ranges(part) for part in parts]
            self._p_detect = [model.reflectors.detection_probabilities(part) for part in parts]
            self._expected = [
                model.expected(part, np.float32, p) for part, p in zip(parts, self._p_detect)
            ]
        cached = zip(chunks, self._map_ranges, self._expected, self._p_detect, strict=True)
        return np.concatenate(
            [
                model.log_likelihood(
                    xy[i : i + _CHUNK], fingerprint, map_ranges=r, expected=e, p_detect=p
                )
                for i, r, e, p in cached
            ]
            or [np.zeros(0)]
        )

    def draw(
        self, loglik: np.ndarray, n: int, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        """``n`` positions drawn in proportion to ``exp(loglik)``, jittered within their cell.

        Returns the positions (n, 2) and the index of the cell each came from (to form the
        importance weight ``L(x) / L(cell)``). Jittered positions that leave the free space
        are put back on their cell centre.
        """
        p = np.exp(loglik - np.max(loglik))
        p /= p.sum()
        cells = rng.choice(len(p), size=n, p=p)
        xy = self.centres_m[cells] + (rng.random((n, 2)) - 0.5) * self.cell_xy_m
        bad = ~self._free(xy)
        xy[bad] = self.centres_m[cells[bad]]
        return xy, cells


@dataclass
class LostTest:
    """CUSUM of the evidence that the robot is outside the particle cloud.

    Attributes
    ----------
    drift_nats : float
        Evidence per frame that a correct cloud may show by chance (the best of many grid
        cells fits the noise a little better than the true position); subtracted per frame.
    drift_per_distance_nats : float
        The same per measured distance: the chance fit grows with the number of distances
        weighed, so a frame's drift is ``max(drift_nats, drift_per_distance_nats * count)``.
    every_frames : int
        While quiet, the test runs on at least one frame in this many (:meth:`due`).
    frames_skipped : int
        Frames skipped since the test last ran.
    last_best_nats : float or None
        The best grid cell's log-likelihood when the test last ran.
    threshold_nats : float
        Statistic at which the cloud counts as lost (probability 1/2).
    statistic_nats : float
        Current CUSUM value (>= 0) of the best cell against the cloud.
    last_deficit_nats : float
        This frame's best-cell log-likelihood minus the cloud's marginal log-likelihood.
    alternative : GridAlternative or None
        A filter over the grid's cells ("the robot is elsewhere"): its predictive likelihood
        against the cloud's marginal is a second CUSUM, ``alternative_nats``, with its own
        drift ``max(alternative_drift_nats, alternative_drift_per_distance_nats x
        distances)`` (:mod:`~lrp_gym.localization.grid_alternative`).
        None: the first statistic alone.
    """

    drift_nats: float = 4.0
    threshold_nats: float = 8.0
    drift_per_distance_nats: float = 0.0
    statistic_nats: float = 0.0
    last_deficit_nats: float = 0.0
    every_frames: int = 1
    frames_skipped: int = 0
    last_best_nats: float | None = None
    alternative: GridAlternative | None = None
    alternative_drift_nats: float = 1.0
    alternative_drift_per_distance_nats: float = 0.0
    alternative_nats: float = 0.0

    def reset(self) -> None:
        self.statistic_nats = 0.0
        self.last_deficit_nats = 0.0
        self.frames_skipped = 0
        self.last_best_nats = None
        self.alternative_nats = 0.0
        if self.alternative is not None:
            self.alternative.reset()

    @classmethod
    def from_config(cls, cfg: LocalizationConfig, grid: MeasurementGrid | None) -> LostTest:
        """The test of ``cfg``'s ``lost_*`` settings; the alternative on ``grid`` (None: none)."""
        drift = cfg.lost_alternative_drift_nats
        use_alternative = drift is not None and grid is not None
        return cls(
            cfg.lost_drift_nats,
            cfg.lost_threshold_nats,
            cfg.lost_drift_per_distance_nats,
            every_frames=cfg.lost_test_every,
            alternative=GridAlternative(grid.cell_index, grid.cell_xy_m)
            if use_alternative
            else None,
            alternative_drift_nats=drift or 0.0,
            alternative_drift_per_distance_nats=cfg.lost_alternative_drift_per_distance_nats,
        )

    def move(self, distance_m: float) -> None:
        """The odometry's translation since the last frame (the alternative's prediction)."""
        if self.alternative is not None:
            self.alternative.move(distance_m)

    @property
    def evidence_nats(self) -> float:
        """The larger of the two statistics: what :attr:`p_lost` and a restart read."""
        return max(self.statistic_nats, self.alternative_nats)

    def drift_for(self, n_distances: int) -> float:
        """A frame's drift: ``max(drift_nats, drift_per_distance_nats * n_distances)``."""
        return max(self.drift_nats, self.drift_per_distance_nats * n_distances)

    def due(self, quiet: bool, marginal: float | None = None, n_distances: int = 0) -> bool:
        """Whether to evaluate the grid and run the test in this frame (always with
        ``every_frames`` 1). It may be skipped, up to ``every_frames - 1`` frames in a row, only
        when ``quiet`` (the filter has converged, no recovery under way), the statistic is 0,
        and the cloud's ``marginal`` log-likelihood of this frame is within the drift, less
        :data:`SKIP_MARGIN_NATS`, of the best cell of the last evaluated grid: a frame that
        could add evidence (a kidnap drops the marginal by many nats) always runs the test."""
        if (
            quiet
            and self.evidence_nats == 0.0
            and self.frames_skipped + 1 < self.every_frames
            and self.last_best_nats is not None
            and marginal is not None
            and self.last_best_nats - marginal <= self.drift_for(n_distances) - SKIP_MARGIN_NATS
        ):
            self.frames_skipped += 1
            return False
        self.frames_skipped = 0
        return True

    @staticmethod
    def marginal(cloud_loglik: np.ndarray, weights: np.ndarray) -> float | None:
        """The cloud's marginal log-likelihood: ``log sum_k w_k L_k`` with the weights
        normalised; None when they sum to 0."""
        total = float(np.sum(weights))
        if not total > 0.0:
            return None
        # Plain numpy: scipy's logsumexp costs ~0.6 ms per call here (env step path).
        top = float(np.max(cloud_loglik))
        with np.errstate(divide="ignore"):  # all weight on -inf particles: -inf, no warning
            return top + float(np.log(np.dot(weights / total, np.exp(cloud_loglik - top))))

    def update(
        self,
        best_loglik: float,
        cloud_loglik: np.ndarray,
        weights: np.ndarray,
        n_distances: int = 0,
    ) -> None:
        """Add one frame: ``cloud_loglik`` (K,) of particles with ``weights`` (K,), from a
        fingerprint of ``n_distances`` measured distances."""
        self.update_marginal(best_loglik, self.marginal(cloud_loglik, weights), n_distances)

    def update_marginal(
        self,
        best_loglik: float,
        marginal: float | None,
        n_distances: int,
        cell_loglik: np.ndarray | None = None,
        cloud_xy: np.ndarray | None = None,
        cloud_weights: np.ndarray | None = None,
        frame_weight: float = 1.0,
    ) -> None:
        """:meth:`update` from the cloud's :meth:`marginal` (None: no frame to add);
        ``cell_loglik``, the frame's grid likelihood, feeds the :attr:`alternative`, whose
        evidence counts the cells away from the cloud (positions ``cloud_xy`` (N, 2) with
        ``cloud_weights`` (N,)).

        ``frame_weight`` in [0, 1] is the share of an independent frame that this one counts
        for (:meth:`FrameEvidence.independence`). Evidence that the cloud is right (a frame
        that lowers a statistic) counts only that share, as in the particle weights: a robot
        standing or turning on the spot sees the same frame again, and a wrong cloud that fits
        it a little better than the drift would otherwise be read as found by repetition
        (docs/trust.md, session 19). Evidence that the cloud is lost counts in full: the odometry
        cannot tell a kidnap at standstill from standing, and a false alarm costs a restart
        where a missed one leaves the estimate confidently wrong."""
        self.last_best_nats = best_loglik
        evidence = None
        if self.alternative is not None and cell_loglik is not None:
            outside = None
            if cloud_xy is not None:
                outside = self.alternative.far_from(cloud_xy, cloud_weights)
            evidence = self.alternative.update(cell_loglik, outside)
        if marginal is None:
            return
        self.last_deficit_nats = best_loglik - marginal
        drift = self.drift_for(n_distances)
        gain = self.last_deficit_nats - drift
        self.statistic_nats = max(0.0, self.statistic_nats + _weighed(gain, frame_weight))
        if evidence is not None and evidence > -np.inf:
            drift = max(
                self.alternative_drift_nats, self.alternative_drift_per_distance_nats * n_distances
            )
            gain = _weighed(evidence - marginal - drift, frame_weight)
            self.alternative_nats = max(0.0, self.alternative_nats + gain)

    @property
    def p_lost(self) -> float:
        """Probability that the cloud has lost the robot, from the statistic (logistic)."""
        return float(1.0 / (1.0 + np.exp(self.threshold_nats - self.evidence_nats)))


def _weighed(gain_nats: float, frame_weight: float) -> float:
    """A statistic's step: a fall (evidence for the cloud) scaled by ``frame_weight``, a rise
    in full (see :meth:`LostTest.update_marginal`)."""
    return gain_nats if gain_nats >= 0.0 else frame_weight * gain_nats


# One copy per model and clutter probability: the grids cache their work per model object.
_LOST_COPIES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def lost_test_model(
    model: FingerprintModel, cfg: LocalizationConfig, cell_xy_m: np.ndarray | None = None
) -> FingerprintModel:
    """The model the lost test weighs with: ``model`` at ``cfg.lost_test_clutter_probability``
    and :func:`lost_test_std_m` (``model`` itself where both match; map, layout and caches
    shared; the same copy on every call).

    The test's drift is calibrated for an outlier class of 0.2; a heavier one lets a lost
    cloud explain most returns as clutter almost as cheaply as a right one, and a kidnap goes
    unnoticed. ``cell_xy_m`` is the lost grid's cell (default: ``cfg.global_grid_m`` square).
    """
    clutter = cfg.lost_test_clutter_probability
    clutter = model.clutter_probability if clutter is None else float(clutter)
    key = (clutter, lost_test_std_m(cfg, cell_xy_m) ** 2)
    if key == (model.clutter_probability, model.measurement_var_m2):
        return model
    copies = _LOST_COPIES.setdefault(model, {})
    if key not in copies:
        other = copy.copy(model)
        other.clutter_probability, other.measurement_var_m2 = key
        copies[key] = other
    return copies[key]


def lost_test_std_m(cfg: LocalizationConfig, cell_xy_m: np.ndarray | None = None) -> float:
    """Range std of the lost test's model: ``cfg.lost_test_std_m``, or (None) the weights'
    ``measurement_std_m`` with the grid's quantisation added. The test weighs cell centres up
    to half a cell from the robot; a uniform offset in an a x b cell adds (a^2 + b^2) / 24 to
    a distance's variance, on average over bearings (for a square cell of 10 cm, 2.9 cm in
    std). Without it a right cloud reads as lost when the std is well below the spacing."""
    if cfg.lost_test_std_m is not None:
        return float(cfg.lost_test_std_m)
    cell = np.full(2, cfg.global_grid_m) if cell_xy_m is None else np.asarray(cell_xy_m, float)
    return float(np.sqrt(cfg.measurement_std_m**2 + np.sum(cell**2) / 24.0))
