"""Noise-free LRP fingerprints of robot positions, vectorised over grids.

A fingerprint is what the radar can know without telling reflectors of one type apart: the
slant distances from the radar phase centre (at the mount height) to every reflector, grouped
by type (in type order) and sorted ascending within each type. Stacked as one row of length M,
two fingerprints can be compared element-wise: for each type, pairing the k-th smallest distance
of one with the k-th smallest of the other is the matching of the two unordered sets that
minimises the largest difference, so the Chebyshev distance of the rows is the bottleneck
distance of the sets.
"""

from __future__ import annotations

import numpy as np


def type_order(type_index: np.ndarray) -> tuple[np.ndarray, list[slice]]:
    """Column order that groups reflectors by type, and the slice of each type in it.

    Parameters
    ----------
    type_index : ndarray of int, shape (M,)

    Returns
    -------
    order : ndarray of int, shape (M,)
        Stable argsort of ``type_index``.
    slices : list of slice
        One slice per type present, in ascending type order.
    """
    type_index = np.asarray(type_index, dtype=int).reshape(-1)
    order = np.argsort(type_index, kind="stable")
    sorted_types = type_index[order]
    edges = np.flatnonzero(np.diff(sorted_types)) + 1
    bounds = np.concatenate([[0], edges, [len(order)]])
    return order, [slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def fingerprints(
    xy_m: np.ndarray,
    reflectors_m: np.ndarray,
    type_index: np.ndarray,
    mount_height_m: float,
) -> np.ndarray:
    """Fingerprints of robot floor positions.

    Parameters
    ----------
    xy_m : ndarray, shape (..., 2)
        Robot floor positions in metres.
    reflectors_m : ndarray, shape (M, 3)
        Reflector phase centres in metres.
    type_index : ndarray of int, shape (M,)
        Type of each reflector.
    mount_height_m : float
        Height of the radar phase centre above the floor.

    Returns
    -------
    ndarray, shape (..., M)
        Slant distances in metres, grouped by type and sorted within each type.
    """
    xy_m = np.asarray(xy_m, dtype=float)
    refl = np.asarray(reflectors_m, dtype=float).reshape(-1, 3)
    order, slices = type_order(type_index)
    refl = refl[order]
    dx = xy_m[..., None, 0] - refl[:, 0]
    dy = xy_m[..., None, 1] - refl[:, 1]
    dz = mount_height_m - refl[:, 2]
    dist = np.sqrt(dx * dx + dy * dy + dz * dz)
    for s in slices:
        if s.stop - s.start > 1:
            dist[..., s] = np.sort(dist[..., s], axis=-1)
    return dist


def quantise(fp: np.ndarray, resolution_m: float) -> np.ndarray:
    """Look-up-table bins of fingerprints: ``floor(d / resolution)`` as int64, same shape."""
    return np.floor(np.asarray(fp, dtype=float) / resolution_m).astype(np.int64)


def unique_fingerprints(fp: np.ndarray, resolution_m: float) -> int:
    """Number of distinct fingerprints (rows of ``fp``, shape (N, M)) after quantisation.

    This is the number of entries of a look-up table that stores one position per quantised
    fingerprint (the paper's count for its layout is 6574 at 0.075 m).
    """
    keys = quantise(np.asarray(fp).reshape(-1, np.shape(fp)[-1]), resolution_m)
    return int(np.unique(keys, axis=0).shape[0])
