"""The room structure's predicted ranges and radial velocities in one compiled pass (numba),
bit-identical to :func:`~lrp_gym.world.structure.structure_ranges_m` and
:func:`~lrp_gym.world.structure.structure_velocities_mps` cast to float32.

The numpy code builds about twenty (returns x positions) float64 arrays per call; this kernel
computes each position's 13 returns in registers and writes the float32 rows directly. It
performs the same IEEE float64 operations in the same order (no ``fastmath``), with the same
``hypot``, and rounds to float32 once, as ``astype`` does, so the results are equal bit for
bit (tested on random positions and velocities, inside the room and beyond its walls). Without
numba :class:`~lrp_gym.localization.map_returns.MapReturns` keeps the numpy functions.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np


def _structure_rows(xy, v, lx, ly, up, out, rates):
    """Fill ``out`` (13, N) float32 (and ``rates`` (13, N) when ``v`` has N rows) in the row
    order of ``structure_ranges_m``: ceiling, 4 wall-ceiling edges, 4 walls, 4 corners."""
    n_pos = xy.shape[0]
    with_v = v.shape[0] == n_pos
    up2 = up**2
    for p in range(n_pos):
        x = xy[p, 0]
        y = xy[p, 1]
        walls = (x, lx - x, y, ly - y)
        out[0, p] = np.float32(up)
        for w in range(4):
            d = walls[w]
            out[1 + w, p] = np.float32(math.sqrt(d**2 + up2))
            out[5 + w, p] = np.float32(d)
        dxs = (0.0 - x, lx - x, 0.0 - x, lx - x)
        dys = (0.0 - y, 0.0 - y, ly - y, ly - y)
        for c in range(4):
            out[9 + c, p] = np.float32(math.hypot(dxs[c], dys[c]))
        if with_v:
            vx = v[p, 0]
            vy = v[p, 1]
            towards = (-vx, vx, -vy, vy)
            rates[0, p] = np.float32(0.0)
            for w in range(4):
                d = walls[w]
                share = d / math.sqrt(d**2 + up2)
                rates[1 + w, p] = np.float32(-towards[w] * share)
                rates[5 + w, p] = np.float32(-towards[w])
            for c in range(4):
                dx = dxs[c]
                dy = dys[c]
                rates[9 + c, p] = np.float32(-(vx * dx + vy * dy) / max(math.hypot(dx, dy), 1e-9))
    return out


structure_rows_jit: Callable[..., Any] | None
try:
    from numba import njit

    structure_rows_jit = njit(cache=True)(_structure_rows)
except ImportError:  # pragma: no cover - numba is in the `fast` extra
    structure_rows_jit = None
