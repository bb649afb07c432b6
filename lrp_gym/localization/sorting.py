"""Sorting the columns of short (m, N) arrays: m expected ranges per position."""

from __future__ import annotations

import numpy as np

_NETWORKS = {
    2: [(0, 1)],
    3: [(0, 1), (1, 2), (0, 1)],
    4: [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)],
}


def sort_rows_inplace(values: np.ndarray) -> np.ndarray:
    """Sort a (m, N) array along axis 0 (each column ascending), in place; returns it.

    For ``m <= 4`` a sorting network of ``np.minimum``/``np.maximum`` on contiguous rows is
    several times faster than ``np.sort(axis=0)``; beyond that ``np.sort``.
    """
    m = values.shape[0]
    if m <= 1:
        return values
    if m > 4:
        values.sort(axis=0)
        return values
    for i, j in _NETWORKS[m]:
        lo = np.minimum(values[i], values[j])
        np.maximum(values[i], values[j], out=values[j])
        values[i] = lo
    return values


def sort_rows_paired_inplace(values: np.ndarray, companion: np.ndarray) -> None:
    """Sort ``values`` (m, N) along axis 0 in place and permute ``companion`` alongside."""
    m = values.shape[0]
    if m <= 1:
        return
    if m > 4:
        order = np.argsort(values, axis=0)
        values[:] = np.take_along_axis(values, order, axis=0)
        companion[:] = np.take_along_axis(companion, order, axis=0)
        return
    for i, j in _NETWORKS[m]:
        swap = values[i] > values[j]
        lo = np.minimum(values[i], values[j])
        np.maximum(values[i], values[j], out=values[j])
        values[i] = lo
        ci = np.where(swap, companion[j], companion[i])
        np.copyto(companion[j], companion[i], where=swap)
        companion[i] = ci
