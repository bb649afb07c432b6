"""The mapped reflectors' distances from floor positions, per type, for the likelihood.

The reflector-major layout keeps each reflector's row contiguous, so the sorting networks
(:mod:`lrp_gym.localization.sorting`) and the per-distance arithmetic work on whole rows with
few numpy calls. With a visibility model (:mod:`lrp_gym.localization.visibility`), a
reflector a position cannot see gets the range
:data:`~lrp_gym.localization.visibility.HIDDEN_RANGE_M` there: it sorts after the visible
ones and matches no measured distance.
"""

from __future__ import annotations

import numpy as np

from lrp_gym.localization.sorting import sort_rows_inplace, sort_rows_paired_inplace
from lrp_gym.localization.visibility import (
    HIDDEN_RANGE_M,
    MIN_DETECTION_PROBABILITY,
    ReflectorVisibility,
    VisibilityMap,
)
from lrp_gym.world.reflectors import ReflectorLayout


class ReflectorRanges:
    """Distances from radar positions to a layout's reflectors, per type.

    Parameters
    ----------
    layout : ReflectorLayout
    mount_height_m : float
        Height of the radar above the floor.
    visibility : VisibilityMap or ReflectorVisibility, optional
        The radar's probability of detecting each reflector from a position; None: every
        reflector everywhere.
    """

    def __init__(
        self,
        layout: ReflectorLayout,
        mount_height_m: float,
        visibility: ReflectorVisibility | VisibilityMap | None = None,
    ) -> None:
        self.visibility = visibility
        #: Each type's reflectors, as indices into the layout.
        self.type_rows = [np.flatnonzero(layout.type_index == t) for t in range(len(layout.types))]
        self._xy = [layout.positions_m[rows, :2].copy() for rows in self.type_rows]
        self._dz2 = [(layout.positions_m[rows, 2] - mount_height_m) ** 2 for rows in self.type_rows]
        self.counts = tuple(len(rows) for rows in self.type_rows)

    def expected(
        self, xy: np.ndarray, dtype=np.float64, p_detect: np.ndarray | None = None
    ) -> list[np.ndarray]:
        """Sorted expected distances per type for positions (N, 2): list of (m_t, N) arrays.

        With a ``visibility``, a reflector a position cannot see has the range
        ``HIDDEN_RANGE_M`` there (after the visible ones: :meth:`visible_counts`);
        ``p_detect``, the :meth:`detection_probabilities` of ``xy``, saves recomputing them.
        """
        out = self.ranges(xy, dtype)
        if self.visibility is not None:
            if p_detect is None:
                p_detect = self.detection_probabilities(xy)
            hidden = p_detect < MIN_DETECTION_PROBABILITY
            for t, d in enumerate(out):
                d[hidden[self.type_rows[t]]] = HIDDEN_RANGE_M
        return [sort_rows_inplace(d) for d in out]

    def ranges(self, xy: np.ndarray, dtype=np.float64) -> list[np.ndarray]:
        """Each reflector's distance per type, in layout order, for positions (N, >= 2):
        list of (m_t, N) arrays (unsorted, hidden or not)."""
        x = xy[:, 0].astype(dtype)
        y = xy[:, 1].astype(dtype)
        out = []
        for rxy, dz2 in zip(self._xy, self._dz2, strict=True):
            dx = x - rxy[:, 0:1].astype(dtype)
            dx *= dx
            dy = y - rxy[:, 1:2].astype(dtype)
            dy *= dy
            dx += dy
            dx += dz2[:, None].astype(dtype)
            out.append(np.sqrt(dx, out=dx))
        return out

    def detection_probabilities(self, xy: np.ndarray) -> np.ndarray | None:
        """The radar's probability (M, N) of detecting each reflector (layout order) from
        positions ``xy`` (N, >= 2) (:class:`ReflectorVisibility`); None without a
        ``visibility`` (every reflector everywhere)."""
        return None if self.visibility is None else self.visibility.detection_probability(xy[:, :2])

    def visible_counts(self, expected: np.ndarray) -> np.ndarray | None:
        """How many reflectors of a type each position sees (N,), from its :meth:`expected`
        ranges (m, N); None without a ``visibility`` (all of them)."""
        if self.visibility is None:
            return None
        return np.count_nonzero(expected < 0.5 * HIDDEN_RANGE_M, axis=0)

    def expected_with_velocity(
        self,
        xy: np.ndarray,
        velocity_xy: np.ndarray,
        dtype=np.float32,
        p_detect: np.ndarray | None = None,
    ) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """Sorted expected distances and, alongside, radial velocities per type.

        ``velocity_xy`` (N, 2) is each position's velocity over the floor; the radial velocity
        of a reflector is positive when its distance grows. Lists of (m_t, N) arrays.
        """
        x = xy[:, 0].astype(dtype)
        y = xy[:, 1].astype(dtype)
        vx = velocity_xy[:, 0].astype(dtype)
        vy = velocity_xy[:, 1].astype(dtype)
        if p_detect is None:
            p_detect = self.detection_probabilities(xy)
        hidden = None if p_detect is None else p_detect < MIN_DETECTION_PROBABILITY
        ranges, rates = [], []
        for t, (rxy, dz2) in enumerate(zip(self._xy, self._dz2, strict=True)):
            dx = rxy[:, 0:1].astype(dtype) - x
            dy = rxy[:, 1:2].astype(dtype) - y
            d = np.sqrt(dx * dx + dy * dy + dz2[:, None].astype(dtype))
            rate = -(vx * dx + vy * dy) / d
            if hidden is not None:
                d[hidden[self.type_rows[t]]] = HIDDEN_RANGE_M
            sort_rows_paired_inplace(d, rate)
            ranges.append(d)
            rates.append(rate)
        return ranges, rates
