"""The lost test's second alternative: "the robot is elsewhere", as a filter over the map.

The lost test's first statistic (:class:`~lrp_gym.localization.proposal.LostTest`) compares
the best cell of each frame's map-wide grid with the particle cloud. The best of thousands of
cells fits a frame's noise better than the true position does, so that comparison pays a drift
of several nats per frame. Under strong unmapped scatterers a wrong cloud explains most returns
almost as well as the truth, and a truth that is better by a few nats in every frame stays
below the drift for as long as the episode lasts: converged, confident and wrong.

This alternative pays the selection once instead of every frame. It is a Bayes filter over the
same grid cells (positions only, like the grid's likelihood), predicted with the odometry's
translation and updated with each frame's grid likelihood. The hypothesis "elsewhere" is its
predicted mass outside the cloud's neighbourhood: the frame's likelihood under that mass
against the cloud's marginal likelihood is a Bayes factor per frame. While the cloud is right
the filter agrees with it and little of its mass lies outside, so the factor is far below zero
however sharp the likelihood (a comparison with all of its mass would pay the cells' coarseness
against the particles, which grows with the number of distances); while the cloud is wrong it
is the truth's advantage over the cloud, once the filter has found the truth.

Without a heading the direction of a move is unknown: a move of ``d`` spreads each cell's mass
over a ring of radius ``d``, here a Gaussian of the ring's variance ``d^2 / 2`` per axis. A
small share of uniform mass each frame lets the filter find the robot again after a kidnap.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter, maximum_filter

#: Share of the predicted mass spread uniformly over the free cells each frame.
UNIFORM_SHARE = 1e-3
#: Floor of the prediction's spread (m): the wheel odometry's noise while standing.
MIN_SPREAD_M = 0.02
#: "Elsewhere" is farther than this (m) from every cell that holds ``NEAR_MASS`` of the
#: cloud's weight: as far as an estimate must be off to count as confidently wrong.
ELSEWHERE_M = 0.3
#: Share of the cloud's weight in a cell that makes its surroundings "the cloud".
NEAR_MASS = 0.01


class GridAlternative:
    """Heading-free histogram filter over a :class:`~lrp_gym.localization.proposal.MeasurementGrid`.

    Parameters
    ----------
    cell_index : ndarray (C, 2) of int
        Each free cell's (column, row) on the grid's lattice.
    cell_m : ndarray (2,)
        The lattice's spacing in x and y (m).
    """

    def __init__(self, cell_index: np.ndarray, cell_m: np.ndarray) -> None:
        self._ij = np.asarray(cell_index, dtype=np.intp)
        self._shape = tuple(self._ij.max(axis=0) + 1) if len(self._ij) else (0, 0)
        self._cell_m = np.asarray(cell_m, dtype=float)
        self.log_p = np.zeros(0)
        self.moved_m = 0.0
        self.reset()

    def reset(self) -> None:
        """Uniform over the free cells; no move pending."""
        n = len(self._ij)
        self.log_p = np.full(n, -np.log(n)) if n else np.zeros(0)
        self.moved_m = 0.0

    def move(self, distance_m: float) -> None:
        """Add a translation reported by the odometry (applied at the next :meth:`update`)."""
        self.moved_m += abs(float(distance_m))

    def far_from(
        self, xy: np.ndarray, weights: np.ndarray, radius_m: float = ELSEWHERE_M
    ) -> np.ndarray:
        """Mask (C,) of "elsewhere": the cells with no cell within about ``radius_m`` (a
        square of cells) that holds ``NEAR_MASS`` of the cloud's weight (positions ``xy``
        (N, 2), ``weights`` (N,)). A minority mode below that share does not hide the cells
        around it: it may be where the robot is."""
        ij = np.clip(np.floor(xy / self._cell_m).astype(np.intp), 0, np.array(self._shape) - 1)
        mass = np.zeros(self._shape)
        np.add.at(mass, (ij[:, 0], ij[:, 1]), weights)
        total = float(np.sum(weights))
        reach = np.ceil(radius_m / self._cell_m - 1e-9).astype(int)
        heaviest = maximum_filter(mass, size=tuple(2 * reach + 1), mode="constant")
        near = heaviest >= NEAR_MASS * total if total > 0.0 else np.zeros(self._shape, bool)
        return ~near[self._ij[:, 0], self._ij[:, 1]]

    def update(self, cell_loglik: np.ndarray, outside: np.ndarray | None = None) -> float:
        """Predict by the moves since the last update, weigh with ``cell_loglik`` (C,); return
        the log of the frame's predictive likelihood over the cells where ``outside`` (C,) is
        True (all cells if None), ``log sum_{c outside} p_pred(c) L(c)`` (-inf if none)."""
        p = np.exp(self.log_p)
        image = np.zeros(self._shape)
        image[self._ij[:, 0], self._ij[:, 1]] = p
        spread_cells = max(self.moved_m / np.sqrt(2.0), MIN_SPREAD_M) / self._cell_m
        image = gaussian_filter(image, spread_cells, mode="constant")
        pred = image[self._ij[:, 0], self._ij[:, 1]]
        pred = (1.0 - UNIFORM_SHARE) * pred / pred.sum() + UNIFORM_SHARE / len(pred)
        log_post = np.log(pred) + cell_loglik
        top = float(np.max(log_post))
        self.moved_m = 0.0
        if not np.isfinite(top):  # no cell explains the frame: start over
            self.reset()
            return top
        terms = np.exp(log_post - top)
        self.log_p = log_post - (top + float(np.log(np.sum(terms))))
        if outside is None:
            return top + float(np.log(np.sum(terms)))
        with np.errstate(divide="ignore"):  # nothing outside: -inf
            return top + float(np.log(np.sum(terms[outside])))
