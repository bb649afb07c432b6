"""Sorting the columns of short (m, N) arrays: m expected ranges per position.

For ``m <= 4`` a sorting network of ``minimum``/``maximum`` per column: compiled (numba) when
it is installed, one pass over the columns with the network in registers; else the same
network on contiguous rows with numpy. Both give the same bits (``minimum`` and ``maximum``
with numpy's NaN rule, a companion swapped where numpy's ``values[i] > values[j]`` swaps it);
the test suite compares them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

_NETWORKS = {
    2: [(0, 1)],
    3: [(0, 1), (1, 2), (0, 1)],
    4: [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)],
}
#: The networks as (comparators, 2) index arrays, for the compiled kernel.
_NETWORK_ARRAYS = {m: np.array(net, dtype=np.int64) for m, net in _NETWORKS.items()}


def _network_columns(values, companion, net):
    """Apply the comparators ``net`` (C, 2) to every column of ``values`` (m, N), swapping
    ``companion`` (m, N) alongside when it has N columns."""
    n_pos = values.shape[1]
    paired = companion.shape[1] == n_pos
    for p in range(n_pos):
        for c in range(net.shape[0]):
            i = net[c, 0]
            j = net[c, 1]
            a = values[i, p]
            b = values[j, p]
            # np.minimum / np.maximum: a NaN operand is returned
            values[i, p] = a if (a < b or np.isnan(a)) else b
            values[j, p] = a if (a >= b or np.isnan(a)) else b
            if paired and a > b:
                t = companion[i, p]
                companion[i, p] = companion[j, p]
                companion[j, p] = t


_network_jit: Callable[..., Any] | None
try:
    from numba import njit

    _network_jit = njit(cache=True)(_network_columns)
except ImportError:  # pragma: no cover - numba is in the `fast` extra; numpy below otherwise
    _network_jit = None


def sort_rows_inplace(values: np.ndarray, use_numba: bool = True) -> np.ndarray:
    """Sort a (m, N) array along axis 0 (each column ascending), in place; returns it.

    For ``m <= 4`` a sorting network (module docstring) is several times faster than
    ``np.sort(axis=0)``; beyond that ``np.sort``.
    """
    m = values.shape[0]
    if m <= 1:
        return values
    if m > 4:
        values.sort(axis=0)
        return values
    if use_numba and _network_jit is not None:
        _network_jit(values, values[:, :0], _NETWORK_ARRAYS[m])
        return values
    for i, j in _NETWORKS[m]:
        lo = np.minimum(values[i], values[j])
        np.maximum(values[i], values[j], out=values[j])
        values[i] = lo
    return values


def sort_rows_paired_inplace(
    values: np.ndarray, companion: np.ndarray, use_numba: bool = True
) -> None:
    """Sort ``values`` (m, N) along axis 0 in place and permute ``companion`` alongside."""
    m = values.shape[0]
    if m <= 1:
        return
    if m > 4:
        order = np.argsort(values, axis=0)
        values[:] = np.take_along_axis(values, order, axis=0)
        companion[:] = np.take_along_axis(companion, order, axis=0)
        return
    if use_numba and _network_jit is not None and companion.shape == values.shape:
        _network_jit(values, companion, _NETWORK_ARRAYS[m])
        return
    for i, j in _NETWORKS[m]:
        swap = values[i] > values[j]
        lo = np.minimum(values[i], values[j])
        np.maximum(values[i], values[j], out=values[j])
        values[i] = lo
        ci = np.where(swap, companion[j], companion[i])
        np.copyto(companion[j], companion[i], where=swap)
        companion[i] = ci
