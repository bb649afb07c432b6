"""Which detections may be a reflector of which type: an RCS window and a range window.

The RCS estimate of a reflector's direct path scatters around its peak (boresight) RCS, and
the incidence-angle pattern of directional reflectors (trihedrals, Van Atta arrays) only ever
lowers it. So the window of type ``t`` is asymmetric::

    peak_t - rcs_tolerance_db - rcs_pattern_loss_db  <=  rcs  <=  peak_t + rcs_tolerance_db

and its centre (used to rank candidates) sits half the pattern loss below the peak. The range
window rejects what no reflector can produce: nothing is nearer than the smallest height
difference between radar and reflector, nothing farther than the farthest reflector from the
farthest corner of the room.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lrp_gym.config import TrackingConfig
from lrp_gym.radar.detections import Detections
from lrp_gym.world.reflectors import ReflectorLayout


def range_limits(
    layout: ReflectorLayout,
    room_size_m: np.ndarray,
    mount_height_m: float,
    margin_m: float = 0.15,
) -> tuple[float, float]:
    """Smallest and largest distance at which a reflector of ``layout`` can be seen.

    The distance to a point is convex in the radar position, so its maximum over the floor
    rectangle (at mount height) is reached at a corner; the minimum is at least the height
    difference between the radar and the reflector.

    Parameters
    ----------
    layout : ReflectorLayout
    room_size_m : array_like, shape (3,)
    mount_height_m : float
        Radar height above the floor.
    margin_m : float
        Widening on both sides (a couple of range bins), so that noise does not cut a
        reflector at the edge of the window.

    Returns
    -------
    (min_range_m, max_range_m) : tuple of float
    """
    lx, ly = float(room_size_m[0]), float(room_size_m[1])
    corners = np.array([[0, 0], [lx, 0], [0, ly], [lx, ly]], dtype=float)
    radar = np.column_stack([corners, np.full(4, mount_height_m)])
    far = float(layout.distances_m(radar).max())
    near = float(np.abs(layout.positions_m[:, 2] - mount_height_m).min())
    return max(near - margin_m, 0.0), far + margin_m


@dataclass(frozen=True)
class LrpClassifier:
    """RCS and range windows of each reflector type.

    Attributes
    ----------
    low_dbsm, high_dbsm : ndarray, shape (T,)
        RCS window of each type.
    centre_dbsm : ndarray, shape (T,)
        Most likely apparent RCS of each type.
    half_width_db : ndarray, shape (T,)
        Half the window's width (scale of the RCS misfit).
    min_range_m, max_range_m : float
        Range window shared by all types.
    """

    low_dbsm: np.ndarray
    high_dbsm: np.ndarray
    centre_dbsm: np.ndarray
    half_width_db: np.ndarray
    min_range_m: float
    max_range_m: float

    @classmethod
    def from_layout(
        cls,
        layout: ReflectorLayout,
        cfg: TrackingConfig,
        *,
        max_range_m: float,
        min_range_m: float = 0.0,
    ) -> LrpClassifier:
        peak = np.array([t.rcs_dbsm for t in layout.types], dtype=float)
        low = peak - cfg.rcs_tolerance_db - cfg.rcs_pattern_loss_db
        high = peak + cfg.rcs_tolerance_db
        centre = (low + high) / 2.0
        # No detection can be a reflector of a type that the layout does not use: empty window.
        low = np.where(layout.counts_per_type() > 0, low, np.inf)
        return cls(
            low_dbsm=low,
            high_dbsm=high,
            centre_dbsm=centre,
            half_width_db=high - centre,
            min_range_m=float(min_range_m),
            max_range_m=float(max_range_m),
        )

    def candidates(self, detections: Detections) -> np.ndarray:
        """Boolean (D, T): detection ``d`` may be a reflector of type ``t``."""
        rcs = detections.rcs_dbsm[:, None]
        r = detections.range_m
        in_range = (r >= self.min_range_m) & (r <= self.max_range_m)
        return (rcs >= self.low_dbsm) & (rcs <= self.high_dbsm) & in_range[:, None]

    def misfit(self, rcs_dbsm: np.ndarray) -> np.ndarray:
        """RCS misfit (..., T): distance from each type's centre in half window widths."""
        return np.abs(np.asarray(rcs_dbsm, dtype=float)[..., None] - self.centre_dbsm) / (
            self.half_width_db
        )

    def classify(self, detections: Detections, cand: np.ndarray | None = None) -> np.ndarray:
        """Best-fitting type of each detection, ``-1`` for clutter; shape (D,).

        ``cand`` is :meth:`candidates` of the same detections, when the caller has it already.
        """
        if cand is None:
            cand = self.candidates(detections)
        if cand.size == 0:
            return np.full(len(detections), -1, dtype=int)
        fit = np.where(cand, self.misfit(detections.rcs_dbsm), np.inf)
        best = np.argmin(fit, axis=1)
        return np.where(cand.any(axis=1), best, -1)
