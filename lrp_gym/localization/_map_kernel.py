"""Density of measured distances under the map-predicted non-reflector returns (numba kernel
with a numpy fallback).

For measured distances ``z_i`` (with ``half_inv_i = -1 / (2 s_i^2)``) and predicted returns
``e_kN`` of weights ``w_k`` (room structure, reflector ghosts) the density term is
``sum_k w_k exp(half_inv_i (e_kN - z_i)^2) D_ikN``, with ``D`` the Doppler density
``a exp(c (u_kN - v_i)^2) + b`` when velocities are given (else 1); the caller multiplies by
the Gaussian's normalisation. Most of the ``n K N`` terms are many standard deviations off:
the kernel skips those below ``exp(CUTOFF)`` of the peak instead of evaluating them, which is
what makes a few dozen predicted returns per particle affordable.

It does not even test them: the measured distances are sorted, so the ones within the cutoff
of a predicted range ``e`` form a run of consecutive indices. The range axis is cut into bins
a fraction (:data:`BINS_PER_WINDOW`) of the widest cutoff window wide; for each bin, the run
of distances that any ``e`` in it could match is found once per call
(:func:`candidate_windows`), and each term looks up its bin's run instead of scanning all
``n`` distances. Narrow bins make the runs hardly longer than the matches, so the cutoff test
inside a run nearly always passes: the branches are predictable, which matters more than the
arithmetic for particles in random order (measured: a sixth less time than window-wide bins).
The runs are a superset of the terms that pass the cutoff test (with a margin for rounding),
the test itself is unchanged and the sums run in the same order, so the result is
bit-identical to the full scan, whatever the bins' width (tested).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

#: Exponent below which a term is skipped (5 standard deviations: exp(-12.5) = 3.7e-6).
CUTOFF = -12.5


def _density_loops(z, half_inv, extra, w, v, extra_v, dopp_a, dopp_b, dopp_c, out):
    n = z.shape[0]
    k_rows, n_pos = extra.shape
    with_v = v.shape[0] == n
    for k in range(k_rows):
        wk = w[k]
        for p in range(n_pos):
            e = extra[k, p]
            for i in range(n):
                r = e - z[i]
                a = r * r * half_inv[i]
                if a < CUTOFF:
                    continue
                val = wk * np.exp(a)
                if with_v:
                    dv = extra_v[k, p] - v[i]
                    val *= dopp_a * np.exp(dopp_c * dv * dv) + dopp_b
                out[i, p] += val
    return out


def _density_binned(z, half_inv, extra, w, v, extra_v, dopp_a, dopp_b, dopp_c, win, out):
    """:func:`_density_loops` with the distances of each term looked up in its bin's run
    ``win = (first (B,), stop (B,), origin, bins per metre)`` instead of scanned."""
    first, stop, origin, per_m = win
    n_bins = first.shape[0]
    k_rows, n_pos = extra.shape
    with_v = v.shape[0] == z.shape[0]
    for k in range(k_rows):
        wk = w[k]
        for p in range(n_pos):
            e = extra[k, p]
            b = (e - origin) * per_m
            if not (b >= 0.0 and b < n_bins):  # beyond every window (also NaN)
                continue
            j = int(b)
            for i in range(first[j], stop[j]):
                r = e - z[i]
                a = r * r * half_inv[i]
                if a < CUTOFF:
                    continue
                val = wk * np.exp(a)
                if with_v:
                    dv = extra_v[k, p] - v[i]
                    val *= dopp_a * np.exp(dopp_c * dv * dv) + dopp_b
                out[i, p] += val
    return out


#: Relative margin of the candidate windows over the cutoff (float32 rounding of the test).
_WINDOW_MARGIN = 1e-3
#: Range bins per cutoff window (:func:`candidate_windows`): any value gives the same sums.
BINS_PER_WINDOW = 16


def candidate_windows(
    z: np.ndarray, half_inv: np.ndarray, bins_per_window: int = BINS_PER_WINDOW
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Per range bin, the run ``[first, stop)`` of the sorted distances ``z`` (n,) that a
    predicted range in the bin can match within the cutoff; the bins' origin and bins per metre.

    With ``w`` the widest window ``max_i sqrt(CUTOFF / half_inv_i)`` (plus a margin), bin ``j``
    holds ranges in ``origin + [j, j + 1) * w / bins_per_window``, from ``w`` below the smallest
    distance to ``w`` above the largest; its run covers the distances within ``w`` of the bin.
    """
    width = float(np.sqrt(np.max(CUTOFF / np.asarray(half_inv, dtype=float))))
    width = width * (1.0 + _WINDOW_MARGIN) + 1e-6
    bin_m = width / bins_per_window
    per_m = 1.0 / bin_m
    zf = np.asarray(z, dtype=float)
    origin = float(zf[0]) - width
    n_bins = int(np.floor((zf[-1] + width - origin) * per_m)) + 2
    lo = origin + np.arange(n_bins) * bin_m
    first = np.searchsorted(zf, lo - width, side="left").astype(np.int64)
    stop = np.searchsorted(zf, lo + bin_m + width, side="right").astype(np.int64)
    return first, stop, origin, per_m


_density_jit: Callable[..., Any] | None
_binned_jit: Callable[..., Any] | None
try:
    from numba import njit

    _density_jit = njit(cache=True, fastmath=True)(_density_loops)
    _binned_jit = njit(cache=True, fastmath=True)(_density_binned)
except ImportError:  # pragma: no cover - numba is in the `fast` extra; numpy below otherwise
    _density_jit = _binned_jit = None


def map_return_density(
    z: np.ndarray,
    half_inv: np.ndarray,
    extra: np.ndarray,
    weights: np.ndarray,
    v: np.ndarray | None = None,
    extra_v: np.ndarray | None = None,
    doppler: tuple[float, float, float] = (1.0, 0.0, 0.0),
    use_numba: bool = True,
) -> np.ndarray:
    """The weighted kernel sum (n, N) described in the module docstring.

    Parameters
    ----------
    z, half_inv : ndarray (n,)
        Measured distances and ``-1 / (2 s^2)`` of each.
    extra : ndarray (K, N)
        Predicted ranges of the map's non-reflector returns per position.
    weights : ndarray (K,)
        Mixture weight of each predicted return.
    v, extra_v : ndarray (n,) and (K, N), optional
        Measured and predicted radial velocities (both or neither).
    doppler : (a, b, c)
        Doppler density ``a exp(c dv^2) + b``.
    use_numba : bool
        Use the compiled kernel when numba is installed (the binned one when ``z`` is
        sorted ascending, else the full scan).
    """
    dtype = extra.dtype.type
    with_v = v is not None and extra_v is not None
    if use_numba and _density_jit is not None:
        out = np.zeros((len(z), extra.shape[1]), dtype=dtype)
        vv = np.asarray(v, dtype=dtype) if with_v else np.zeros(0, dtype=dtype)
        ev = np.asarray(extra_v, dtype=dtype) if with_v else np.zeros((1, 1), dtype=dtype)
        a, b, c = (dtype(x) for x in doppler)
        args = (
            np.asarray(z, dtype=dtype),
            np.asarray(half_inv, dtype=dtype),
            extra,
            np.asarray(weights, dtype=dtype),
            vv,
            ev,
            a,
            b,
            c,
        )
        if len(z) and _binned_jit is not None and bool(np.all(np.diff(z) >= 0.0)):
            return _binned_jit(*args, candidate_windows(z, half_inv, BINS_PER_WINDOW), out)
        return _density_jit(*args, out)
    return _density_numpy(z, half_inv, extra, weights, v, extra_v, doppler, with_v)


def _density_numpy(z, half_inv, extra, weights, v, extra_v, doppler, with_v) -> np.ndarray:
    """The numpy fallback of :func:`map_return_density`: every term, no cutoff."""
    dtype = extra.dtype.type
    rs = extra[None, :, :] - np.asarray(z, dtype=dtype)[:, None, None]  # (n, K, N)
    rs *= rs
    rs *= np.asarray(half_inv, dtype=dtype)[:, None, None]
    np.exp(rs, out=rs)
    if with_v:
        a, b, c = (dtype(x) for x in doppler)
        dv = np.asarray(extra_v)[None, :, :] - np.asarray(v, dtype=dtype)[:, None, None]
        dv *= dv
        dv *= c
        np.exp(dv, out=dv)
        dv *= a
        dv += b
        rs *= dv
    return np.einsum("k,nkN->nN", np.asarray(weights, dtype=dtype), rs)
