"""Ghost ranges of :class:`~lrp_gym.localization.ghosts.GhostModel` in one compiled pass
(numba), bit-identical to its numpy code in float32.

The numpy code builds a dozen (images x reflectors x positions) arrays per call, one pass over
memory each; this kernel computes them for blocks of positions that stay in cache, in
branch-free loops that the compiler vectorises, and writes the ghost rows directly. It
performs the same IEEE float32 operations in the same order as the numpy code (no
``fastmath``: no reassociation, no fused multiply-add; vector lanes round like scalars), so
the results are equal bit for bit; the test suite checks this on random positions,
velocities and layouts. Without numba :meth:`GhostModel.ranges` keeps its numpy path.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

#: Positions per block: the per-block work arrays (images x reflectors x block) stay in cache.
_BLOCK = 512


def _ghost_rows(xy, v, sign, offset, pos, dz, axes, cos_vis, cos_beta_min, groups, far, out, rates):
    """Fill ``out`` (G, N) (and ``rates`` (G, N) when ``v`` has N rows) for positions ``xy``.

    ``groups`` (R, 4) lists the output rows: image a, image b, reflector m, and whether the
    row is a retro-directive bistatic pair (which needs the retro-lobe test).

    Blocks of positions, each loop over the positions of a block and branch-free, so that the
    compiler vectorises them (IEEE float32 lanes: the same bits as one position at a time).
    """
    n_pos = xy.shape[0]
    n_img, n_ref = dz.shape
    with_v = v.shape[0] == n_pos
    half = np.float32(0.5)
    one, zero = np.float32(1.0), np.float32(0.0)
    blk = _BLOCK
    xs = np.empty(blk, dtype=np.float32)
    ys = np.empty(blk, dtype=np.float32)
    vxs = np.empty(blk, dtype=np.float32)
    vys = np.empty(blk, dtype=np.float32)
    dx = np.empty((n_img, n_ref, blk), dtype=np.float32)
    dy = np.empty((n_img, n_ref, blk), dtype=np.float32)
    dist = np.empty((n_img, n_ref, blk), dtype=np.float32)
    vis = np.empty((n_img, n_ref, blk), dtype=np.float32)  # 1 or 0 (vectorises, unlike bool)
    rate = np.empty((n_img, n_ref, blk), dtype=np.float32)
    ok = np.empty(blk, dtype=np.bool_)
    for p0 in range(0, n_pos, blk):
        nb = min(blk, n_pos - p0)
        for q in range(nb):
            xs[q] = xy[p0 + q, 0]
            ys[q] = xy[p0 + q, 1]
        if with_v:
            for q in range(nb):
                vxs[q] = v[p0 + q, 0]
                vys[q] = v[p0 + q, 1]
        for i in range(n_img):
            s0, s1 = sign[i, 0], sign[i, 1]
            o0, o1 = offset[i, 0], offset[i, 1]
            for m in range(n_ref):
                px, py = pos[m, 0], pos[m, 1]
                ddz = dz[i, m]
                dz2 = ddz * ddz
                cz = ddz * axes[m, 2]
                a0, a1, cv = axes[m, 0], axes[m, 1], cos_vis[m]
                dxr, dyr, dr, vr = dx[i, m], dy[i, m], dist[i, m], vis[i, m]
                for q in range(nb):
                    # (sign * x) in float32, + offset in float64, back to float32: as numpy does
                    ix = np.float32(np.float64(s0 * xs[q]) + o0)
                    iy = np.float32(np.float64(s1 * ys[q]) + o1)
                    ddx = ix - px
                    ddy = iy - py
                    d = np.sqrt(ddx * ddx + ddy * ddy + dz2)
                    c = (ddx * a0 + ddy * a1 + cz) / d
                    dxr[q] = ddx
                    dyr[q] = ddy
                    dr[q] = d
                    vr[q] = one if c >= cv else zero
                if with_v:
                    rr = rate[i, m]
                    for q in range(nb):
                        rr[q] = (dxr[q] * (s0 * vxs[q]) + dyr[q] * (s1 * vys[q])) / dr[q]
        for row in range(groups.shape[0]):
            a, b, m = groups[row, 0], groups[row, 1], groups[row, 2]
            va, vb, da, db = vis[a, m], vis[b, m], dist[a, m], dist[b, m]
            if groups[row, 3] == 1:
                dzz = dz[b, m] * dz[a, m]
                xa, xb, ya, yb = dx[a, m], dx[b, m], dy[a, m], dy[b, m]
                for q in range(nb):
                    cb = (xb[q] * xa[q] + yb[q] * ya[q] + dzz) / (db[q] * da[q])
                    ok[q] = (va[q] * vb[q] > zero) & (cb >= cos_beta_min)
            else:
                for q in range(nb):
                    ok[q] = va[q] * vb[q] > zero
            o = out[row]
            if a == b:  # same face out and back: the numpy code takes the distance itself
                for q in range(nb):
                    o[p0 + q] = da[q] if ok[q] else far
            else:
                for q in range(nb):
                    o[p0 + q] = half * (da[q] + db[q]) if ok[q] else far
            if with_v:
                ra, rb, rt = rate[a, m], rate[b, m], rates[row]
                if a == b:
                    for q in range(nb):
                        rt[p0 + q] = ra[q]
                else:
                    for q in range(nb):
                        rt[p0 + q] = half * (ra[q] + rb[q])
    return out


ghost_rows_jit: Callable[..., Any] | None
try:
    from numba import njit

    # numpy's error model: no zero-division checks, which would keep the loops scalar
    ghost_rows_jit = njit(cache=True, error_model="numpy")(_ghost_rows)
except ImportError:  # pragma: no cover - numba is in the `fast` extra
    ghost_rows_jit = None
