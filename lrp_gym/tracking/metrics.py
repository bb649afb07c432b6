"""Scoring a tracker against the true distances: matched errors, track swaps, missed frames."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from lrp_gym.tracking.tracker import TrackView


def matched_errors_m(estimates_m: np.ndarray, truth_m: np.ndarray) -> np.ndarray:
    """Errors of the best one-to-one match of estimates to true distances (Hungarian on |diff|).

    Parameters
    ----------
    estimates_m, truth_m : array_like, shape (E,) and (M,)
        Unordered distances of one reflector type.

    Returns
    -------
    ndarray, shape (min(E, M),)
        ``estimate - truth`` of each matched pair; unmatched entries are not scored.
    """
    est = np.asarray(estimates_m, dtype=float).reshape(-1)
    tru = np.asarray(truth_m, dtype=float).reshape(-1)
    if len(est) == 0 or len(tru) == 0:
        return np.zeros(0)
    diff = est[:, None] - tru[None, :]
    rows, cols = linear_sum_assignment(np.abs(diff))
    return diff[rows, cols]


def per_type_errors_m(
    estimates_by_type: Sequence[np.ndarray], truth_m: np.ndarray, type_index: np.ndarray
) -> np.ndarray:
    """:func:`matched_errors_m` for every type, concatenated."""
    parts = [
        matched_errors_m(est, truth_m[type_index == t]) for t, est in enumerate(estimates_by_type)
    ]
    return np.concatenate(parts) if parts else np.zeros(0)


class SwapCounter:
    """Counts frames in which a confirmed track follows a different reflector than before.

    Each frame, the confirmed tracks of a type are matched to that type's reflectors
    (Hungarian on |track distance - true distance|); a track's reflector is its identity. A
    change counts as a swap only when the two reflectors' true distances differ by more than
    ``tolerance_m`` (when they are nearly equal the fingerprint is the same either way, and
    the track keeps its previous identity).

    Parameters
    ----------
    type_index : ndarray of int, shape (M,)
        Type of each reflector.
    tolerance_m : float
        Distance difference below which a change of reflector does not count.
    """

    def __init__(self, type_index: np.ndarray, tolerance_m: float = 0.075) -> None:
        self.type_index = np.asarray(type_index, dtype=int)
        self.tolerance_m = tolerance_m
        self._identity: dict[int, int] = {}
        self.swaps = 0

    def update(self, tracks: Sequence[TrackView], truth_m: np.ndarray) -> bool:
        """Record one frame; return whether it had a swap."""
        swapped = False
        identity: dict[int, int] = {}
        for ty in np.unique(self.type_index):
            refl = np.flatnonzero(self.type_index == ty)
            conf = [t for t in tracks if t.type_index == ty and t.status == "confirmed"]
            if not conf:
                continue
            d = np.array([t.distance_m for t in conf])
            rows, cols = linear_sum_assignment(np.abs(d[:, None] - truth_m[refl][None, :]))
            for r, c in zip(rows, cols, strict=True):
                tid, new = conf[r].track_id, int(refl[c])
                old = self._identity.get(tid)
                if old is not None and old != new:
                    if abs(truth_m[old] - truth_m[new]) > self.tolerance_m:
                        swapped = True
                    else:
                        new = old  # ambiguous while the distances cross: keep the identity
                identity[tid] = new
        self._identity = identity
        self.swaps += int(swapped)
        return swapped
