"""Greedy merging of paths into resolution cells (numba kernel with a numpy fallback)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np


def greedy_owner_numpy(near: np.ndarray) -> np.ndarray:
    """Owner of each path: the first (strongest) earlier head it is near, else itself.

    ``near`` (P, P) is symmetric; paths are sorted by decreasing power.
    """
    owner = np.arange(len(near))
    for i in np.flatnonzero(np.triu(near, 1).any(axis=0)):  # only paths with a stronger neighbour
        cand = np.flatnonzero(near[:i, i] & (owner[:i] == np.arange(i)))
        if len(cand):
            owner[i] = cand[0]
    return owner


def _greedy_owner_loops(rb, db, res_r, res_d, nc):
    n = rb.shape[0]
    owner = np.arange(n)
    for i in range(n):
        for j in range(i):
            if owner[j] != j:
                continue
            dd = (db[i] - db[j] + nc / 2) % nc - nc / 2
            if abs(rb[i] - rb[j]) < res_r and abs(dd) < res_d:
                owner[i] = j
                break
    return owner


_greedy_owner_jit: Callable[..., Any] | None
try:
    from numba import njit

    _greedy_owner_jit = njit(cache=True)(_greedy_owner_loops)
except ImportError:  # pragma: no cover - numba is a dependency, the fallback keeps it optional
    _greedy_owner_jit = None


def greedy_owner(rb, db, res_r: float, res_d: float, nc: int, use_numba: bool = True):
    """Merge owner per path (see :func:`greedy_owner_numpy`), from fractional bins."""
    if use_numba and _greedy_owner_jit is not None:
        return _greedy_owner_jit(rb, db, float(res_r), float(res_d), float(nc))
    dr = rb[:, None] - rb[None, :]
    dd = (db[:, None] - db[None, :] + nc / 2) % nc - nc / 2
    return greedy_owner_numpy((np.abs(dr) < res_r) & (np.abs(dd) < res_d))
