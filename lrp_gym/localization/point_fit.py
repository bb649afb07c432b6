"""Range-only geometry of one static point seen by a radar moving in a plane.

A point at floor position ``q`` and height ``h`` off the radar's plane is at distance
``sqrt(|p - q|^2 + h^2)`` from the radar at ``p``: from a plane, the point and its mirror
image give the same distances, so ``h`` is its height above or below the radar. Used by the
clutter map (:mod:`lrp_gym.localization.clutter_map`) to find and fit unmapped scatterers.
"""

from __future__ import annotations

import itertools

import numpy as np
from scipy.optimize import least_squares

#: Residual evaluations of one fit, at most.
_MAX_EVALUATIONS = 50


def fit_point(
    radar_xy: np.ndarray, ranges_m: np.ndarray, start: np.ndarray | None = None
) -> tuple[np.ndarray, float]:
    """The static point that best explains distances measured from radar positions in a plane.

    Parameters
    ----------
    radar_xy : ndarray (K, 2)
        Radar positions over the floor (all at the same height), m.
    ranges_m : ndarray (K,)
        Distances measured from them, m.
    start : ndarray (3,), optional
        A point to refine (a refit); else the linear solution below.

    Returns
    -------
    point : ndarray (3,)
        ``(x_m, y_m, h_m)``: floor position and height above (or below) the radar plane.
    rms_m : float
        RMS of the distance residuals.

    Notes
    -----
    ``r^2 - |p|^2 = -2 p.q + (|q|^2 + h^2)`` is linear in ``(q, c = |q|^2 + h^2)``: a linear
    least-squares start, then ``scipy.optimize.least_squares`` on the distances themselves.
    """
    p = np.asarray(radar_xy, dtype=float)
    r = np.asarray(ranges_m, dtype=float)
    if start is None:
        a = np.column_stack([-2.0 * p, np.ones(len(p))])
        sol, *_ = np.linalg.lstsq(a, r**2 - np.sum(p**2, axis=1), rcond=None)
        q = sol[:2]
        x = np.array([*q, float(np.sqrt(max(sol[2] - q @ q, 1e-4)))])
    else:
        x = np.asarray(start, dtype=float).copy()

    def residuals(v: np.ndarray) -> np.ndarray:
        return np.sqrt((v[0] - p[:, 0]) ** 2 + (v[1] - p[:, 1]) ** 2 + v[2] ** 2) - r

    def jacobian(v: np.ndarray) -> np.ndarray:
        d = np.column_stack([v[0] - p[:, 0], v[1] - p[:, 1], np.full(len(p), v[2])])
        return d / np.maximum(np.linalg.norm(d, axis=1), 1e-9)[:, None]

    # Levenberg-Marquardt (a start near the answer: the linear solution or the last fit).
    x = least_squares(residuals, x, jac=jacobian, method="lm", max_nfev=_MAX_EVALUATIONS).x
    x[2] = abs(x[2])  # a point and its mirror image in the radar's plane are the same
    pred = np.sqrt((x[0] - p[:, 0]) ** 2 + (x[1] - p[:, 1]) ** 2 + x[2] ** 2)
    return x, float(np.sqrt(np.mean((r - pred) ** 2)))


def cross_spread_m(radar_xy: np.ndarray) -> float:
    """Std of the positions across their main direction (0 for positions on one line)."""
    p = np.asarray(radar_xy, dtype=float)
    if len(p) < 3:
        return 0.0
    return float(np.sqrt(max(np.linalg.eigvalsh(np.cov(p.T))[0], 0.0)))


def point_hypotheses(
    radar_xy: np.ndarray, ranges_m: list[np.ndarray], min_spread_m: float, anchors: int = 5
) -> np.ndarray:
    """Candidate static points (H, 3) from triples of buffered frames.

    ``anchors`` frames spread evenly over the buffer; every triple of them whose positions
    span a triangle (not a line: ``min_spread_m``) and every choice of one distance per frame
    of the triple is solved exactly (three equations of :func:`fit_point`'s linear form).
    A point missed in some frames is still found from the triples that saw it. Without
    randomness, so a seed still fixes the run.
    """
    p = np.asarray(radar_xy, dtype=float)
    picks = np.unique(np.linspace(0, len(p) - 1, anchors).round().astype(int))
    out = []
    for i, j, k in itertools.combinations(picks, 3):
        zs = [ranges_m[i], ranges_m[j], ranges_m[k]]
        q = p[[i, j, k]]
        # Twice the triangle's area over its longest side: the height of the triangle.
        u, v = q[1] - q[0], q[2] - q[0]
        area2 = abs(u[0] * v[1] - u[1] * v[0])
        side = max(np.linalg.norm(q[1] - q[0]), np.linalg.norm(q[2] - q[0]), 1e-9)
        if any(len(z) == 0 for z in zs) or area2 / side < min_spread_m:
            continue
        r = np.stack(np.meshgrid(*zs, indexing="ij"), axis=-1).reshape(-1, 3)
        a_mat = np.column_stack([-2.0 * q, np.ones(3)])
        sol = np.linalg.solve(a_mat, (r**2 - np.sum(q**2, axis=1)).T).T  # qx, qy, c
        h2 = sol[:, 2] - np.sum(sol[:, :2] ** 2, axis=1)
        ok = h2 > -0.05  # a small negative h^2 is noise on a point in the radar's plane
        out.append(np.column_stack([sol[ok, :2], np.sqrt(np.maximum(h2[ok], 0.0))]))
    return np.concatenate(out) if out else np.zeros((0, 3))


def inside_room(points: np.ndarray, size_m: np.ndarray, margin_m: float = 0.1) -> np.ndarray:
    """Which points (P, 3) lie over the room's floor (within ``margin_m``) and no higher off
    the radar's plane than the room is tall."""
    return (
        np.all(points[:, :2] >= -margin_m, axis=1)
        & np.all(points[:, :2] <= size_m[:2] + margin_m, axis=1)
        & (points[:, 2] <= size_m[2])
    )


def nearest_distances(pred: np.ndarray, ranges_m: list[np.ndarray]) -> np.ndarray:
    """Per hypothesis and frame (H, K), the frame's distance nearest ``pred`` (inf without
    any): one sorted search over all frames, each frame's distances shifted apart."""
    h, k = pred.shape
    span = (
        2.0
        * max(float(np.max(pred, initial=0.0)), *(float(np.max(z, initial=0.0)) for z in ranges_m))
        + 1.0
    )
    z = np.concatenate([np.sort(zk) + i * span for i, zk in enumerate(ranges_m)] + [np.zeros(0)])
    if not len(z):
        return np.full(pred.shape, np.inf)
    q = pred + np.arange(k)[None, :] * span
    idx = np.searchsorted(z, q)
    lo = z[np.clip(idx - 1, 0, len(z) - 1)]
    hi = z[np.clip(idx, 0, len(z) - 1)]
    out = np.where(np.abs(lo - q) <= np.abs(hi - q), lo, hi) - np.arange(k)[None, :] * span
    # A neighbour from another frame is more than ``span`` / 2 away: no distance in this one.
    return np.where(np.abs(out - pred) < span / 2.0, out, np.inf)
