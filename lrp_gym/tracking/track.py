"""One track's state, and the read-only view of it that the tracker hands out."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from lrp_gym.tracking.fingerprint import Fingerprint

NIS_EXPECTED = 2.0  # mean of a chi-square with 2 degrees of freedom: a well-modelled track


@dataclass(frozen=True)
class TrackView:
    """Read-only snapshot of one track, for plotting and debugging.

    Attributes
    ----------
    track_id : int
        Unique within a tracker run (restarts at 0 after :meth:`LrpTracker.reset`).
    type_index : int
    type_name : str
    distance_m, rate_mps : float
        Filtered state after this frame.
    variance_m2 : float
        Variance of ``distance_m``.
    rcs_dbsm : float
        Running mean of the RCS estimates of the detections the track took.
    status : {"tentative", "candidate", "confirmed"}
        ``confirmed``: reported as a reflector; ``candidate``: a persistent return that is
        not (or no longer) believed to be one; ``tentative``: not yet M-of-N.
    age : int
        Frames since the track started (1 in its first frame).
    misses : int
        Consecutive frames without a detection.
    fresh : bool
        Updated by a detection in this frame.
    nis : float
        Running mean of the normalised innovation squared (2 on average for a return that
        behaves as the motion model predicts).
    """

    track_id: int
    type_index: int
    type_name: str
    distance_m: float
    rate_mps: float
    variance_m2: float
    rcs_dbsm: float
    status: Literal["tentative", "candidate", "confirmed"]
    age: int
    misses: int
    fresh: bool
    nis: float


class Track:
    """Mutable track state around one filterpy Kalman filter."""

    __slots__ = (
        "track_id",
        "type_index",
        "x",
        "P",
        "rcs_dbsm",
        "hits",
        "age",
        "misses",
        "persistent",
        "fresh",
        "nis",
        "slot",
    )

    def __init__(
        self, track_id: int, type_index: int, x: np.ndarray, P: np.ndarray, rcs_dbsm: float
    ) -> None:
        self.track_id = track_id
        self.type_index = type_index
        self.x = x  # (2,) distance_m, rate_mps
        self.P = P  # (2, 2) its covariance
        self.rcs_dbsm = rcs_dbsm
        self.hits = 1  # bit i set: hit i frames ago
        self.age = 1
        self.misses = 0
        self.persistent = False  # passed M of N (status "candidate" until reported as "confirmed")
        self.fresh = True
        self.nis = NIS_EXPECTED
        self.slot = -1  # reflector slot of its type while reported, else -1

    @property
    def selected(self) -> bool:
        """Reported as one of its type's reflectors."""
        return self.slot >= 0

    @property
    def status(self) -> Literal["tentative", "candidate", "confirmed"]:
        if self.selected:
            return "confirmed"
        return "candidate" if self.persistent else "tentative"


def tracks_fingerprint(
    type_names: tuple[str, ...], tracks_by_type: list[list[Track]], fresh_by_type: list[list[bool]]
) -> Fingerprint:
    """The fingerprint of given tracks per type: filtered distances, variances, fresh flags."""
    dists, variances, fresh = [], [], []
    for tracks, flags in zip(tracks_by_type, fresh_by_type, strict=True):
        d = np.array([t.x[0] for t in tracks], dtype=float)
        order = np.argsort(d, kind="stable")
        dists.append(d[order])
        variances.append(np.array([t.P[0, 0] for t in tracks], dtype=float)[order])
        fresh.append(np.array(flags, dtype=bool)[order])
    return Fingerprint(type_names, tuple(dists), tuple(variances), tuple(fresh))
