"""Ghost ranges of :class:`~lrp_gym.localization.ghosts.GhostModel` in one compiled pass
(numba), bit-identical to its numpy code in float32.

The numpy code builds a dozen (images x reflectors x positions) arrays per call, one pass over
memory each; this kernel computes each position's image offsets, distances, visibility and
rates in registers and writes the ghost rows directly. It performs the same IEEE float32
operations in the same order as the numpy code (no ``fastmath``: no reassociation, no fused
multiply-add), so the results are equal bit for bit; the test suite checks this on random
positions, velocities and layouts. Without numba :meth:`GhostModel.ranges` keeps its numpy
path.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np


def _ghost_rows(xy, v, sign, offset, pos, dz, axes, cos_vis, cos_beta_min, groups, far, out, rates):
    """Fill ``out`` (G, N) (and ``rates`` (G, N) when ``v`` has N rows) for positions ``xy``.

    ``groups`` (R, 4) lists the output rows: image a, image b, reflector m, and whether the
    row is a retro-directive bistatic pair (which needs the retro-lobe test).
    """
    n_pos = xy.shape[0]
    n_img, n_ref = dz.shape
    with_v = v.shape[0] == n_pos
    half = np.float32(0.5)
    dx = np.empty((n_img, n_ref), dtype=np.float32)
    dy = np.empty((n_img, n_ref), dtype=np.float32)
    dist = np.empty((n_img, n_ref), dtype=np.float32)
    vis = np.empty((n_img, n_ref), dtype=np.bool_)
    rate = np.empty((n_img, n_ref), dtype=np.float32)
    for p in range(n_pos):
        x = xy[p, 0]
        y = xy[p, 1]
        for i in range(n_img):
            # (sign * x) in float32, + offset in float64, back to float32: as numpy does
            ix = np.float32(np.float64(sign[i, 0] * x) + offset[i, 0])
            iy = np.float32(np.float64(sign[i, 1] * y) + offset[i, 1])
            for m in range(n_ref):
                ddx = ix - pos[m, 0]
                ddy = iy - pos[m, 1]
                ddz = dz[i, m]
                d = np.sqrt(ddx * ddx + ddy * ddy + ddz * ddz)
                c = ddx * axes[m, 0] + ddy * axes[m, 1] + ddz * axes[m, 2]
                c = c / d
                dx[i, m] = ddx
                dy[i, m] = ddy
                dist[i, m] = d
                vis[i, m] = c >= cos_vis[m]
                if with_v:
                    r = ddx * (sign[i, 0] * v[p, 0]) + ddy * (sign[i, 1] * v[p, 1])
                    rate[i, m] = r / d
        for row in range(groups.shape[0]):
            a = groups[row, 0]
            b = groups[row, 1]
            m = groups[row, 2]
            ok = vis[a, m] and vis[b, m]
            if groups[row, 3] == 1 and ok:
                cb = dx[b, m] * dx[a, m] + dy[b, m] * dy[a, m]
                cb = cb + dz[b, m] * dz[a, m]
                cb = cb / (dist[b, m] * dist[a, m])
                ok = cb >= cos_beta_min
            if a == b:  # same face out and back: the numpy code takes the distance itself
                out[row, p] = dist[a, m] if ok else far
                if with_v:
                    rates[row, p] = rate[a, m]
            else:
                out[row, p] = half * (dist[a, m] + dist[b, m]) if ok else far
                if with_v:
                    rates[row, p] = half * (rate[a, m] + rate[b, m])
    return out


ghost_rows_jit: Callable[..., Any] | None
try:
    from numba import njit

    ghost_rows_jit = njit(cache=True)(_ghost_rows)
except ImportError:  # pragma: no cover - numba is in the `fast` extra
    ghost_rows_jit = None
