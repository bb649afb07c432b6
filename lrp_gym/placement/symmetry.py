"""Systematic ambiguities: the symmetries of same-type reflector pairs, and the layout constraint.

With all reflectors at one height the problem is planar (slant distance is a monotone function
of the horizontal distance). Two reflectors a, b of one type cannot be told apart, so a position
p has the same two distances as its three images

- the mirror image in the line through a and b (distances kept),
- the mirror image in their perpendicular bisector (distances swapped),
- the point mirror through their midpoint m (distances swapped).

A third reflector c breaks these, except on the *ambiguity line* through m orthogonal to
m - c (there the point mirror keeps the distance to c). With a complementary pair c, d the point
mirror through m keeps {d_c, d_d} on a whole line exactly when m lies on the line through c and
d (both kept) or on their perpendicular bisector (swapped, only if c and d share a type). The
layout constraint of four reflectors is therefore: no symmetry axis of a same-type pair passes
(within a tolerance) through the midpoint of its complementary pair. With two types (2 + 2) only
the two same-type pairs are checked.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import combinations

import numpy as np


def same_type_pairs(type_index: np.ndarray) -> np.ndarray:
    """Index pairs (P, 2), i < j, of reflectors that share a type."""
    t = np.asarray(type_index, dtype=int).reshape(-1)
    pairs = [(i, j) for i, j in combinations(range(len(t)), 2) if t[i] == t[j]]
    return np.array(pairs, dtype=int).reshape(-1, 2)


def pair_images(
    reflectors_xy_m: np.ndarray, type_index: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The three image maps of every same-type pair as affine maps ``p -> A p + b``.

    Parameters
    ----------
    reflectors_xy_m : ndarray, shape (M, 2)
        Horizontal reflector positions in metres.
    type_index : ndarray of int, shape (M,)

    Returns
    -------
    A : ndarray, shape (G, 2, 2)
    b : ndarray, shape (G, 2)
        ``G = 3 * P`` maps, per pair: mirror in the pair's line, in its perpendicular
        bisector, and the point mirror through its midpoint. All are isometric involutions.
    """
    xy = np.asarray(reflectors_xy_m, dtype=float)[:, :2]
    pairs = same_type_pairs(type_index)
    mats, offs = [], []
    for i, j in pairs:
        m = (xy[i] + xy[j]) / 2.0
        e = xy[j] - xy[i]
        e = e / max(np.linalg.norm(e), 1e-12)
        ee = np.outer(e, e)
        for a in (2.0 * ee - np.eye(2), np.eye(2) - 2.0 * ee, -np.eye(2)):
            mats.append(a)
            offs.append(m - a @ m)
    return np.array(mats).reshape(-1, 2, 2), np.array(offs).reshape(-1, 2)


def _line_distance(point: np.ndarray, origin: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Distance (...) of points (..., 2) from lines through ``origin`` along ``direction``."""
    d = direction / np.maximum(np.linalg.norm(direction, axis=-1, keepdims=True), 1e-12)
    r = point - origin
    return np.abs(r[..., 0] * d[..., 1] - r[..., 1] * d[..., 0])


def constraint_checks(
    type_index: np.ndarray,
) -> list[tuple[tuple[int, int], tuple[int, int], bool]]:
    """The (pair P, pair Q, check bisector) tests of the constraint.

    For every same-type pair P and every pair Q of the other reflectors when there are at least
    two: the line through Q must miss P's midpoint; Q's bisector must miss it too when Q is a
    same-type pair. For exactly four reflectors this is the paper's condition; for more it is
    conservative (a further reflector would break the line).
    """
    t = np.asarray(type_index, dtype=int).reshape(-1)
    checks = []
    for p in same_type_pairs(t):
        others = [k for k in range(len(t)) if k not in p]
        for q in combinations(others, 2):
            checks.append(((int(p[0]), int(p[1])), q, bool(t[q[0]] == t[q[1]])))
    return checks


def constraint_margins(reflectors_xy_m: np.ndarray, type_index: np.ndarray) -> np.ndarray:
    """Smallest distance of a same-type midpoint to a complementary symmetry axis.

    Parameters
    ----------
    reflectors_xy_m : ndarray, shape (..., M, 2)
        One or a batch of layouts.
    type_index : ndarray of int, shape (M,)

    Returns
    -------
    ndarray, shape (...)
        Margin in metres (``inf`` when there is nothing to check). The constraint holds when
        the margin exceeds the tolerance.
    """
    xy = np.asarray(reflectors_xy_m, dtype=float)[..., :2]
    checks = constraint_checks(type_index)
    if not checks:
        return np.full(xy.shape[:-2], np.inf)
    # All checks at once (an index per check): eight same-type reflectors have 840 of them,
    # and a Python loop over them made the layout search's rejection sampling take minutes.
    i, j, k, n = np.array([[*p, *q] for p, q, _ in checks], dtype=int).T
    bisector = np.array([b for *_, b in checks])
    mid = (xy[..., i, :] + xy[..., j, :]) / 2.0
    q_mid = (xy[..., k, :] + xy[..., n, :]) / 2.0
    q_dir = xy[..., n, :] - xy[..., k, :]
    out = np.min(_line_distance(mid, q_mid, q_dir), axis=-1)
    if bisector.any():
        normal = np.stack([-q_dir[..., 1], q_dir[..., 0]], axis=-1)
        dist = _line_distance(
            mid[..., bisector, :], q_mid[..., bisector, :], normal[..., bisector, :]
        )
        out = np.minimum(out, np.min(dist, axis=-1))
    return out


@dataclass(frozen=True)
class ConstraintReport:
    """Whether a layout is free of systematic ambiguities.

    Attributes
    ----------
    ok : bool
        No systematic structure: every same-type pair is broken by at least two other
        reflectors, and no axis passes within the tolerance of a complementary midpoint.
    margin_m : float
        Smallest midpoint-to-axis distance (``inf`` when nothing is checked).
    structures : tuple of str
        Human-readable systematic structures found (inherent ones for 2 or 3 reflectors,
        and constraint violations).
    """

    ok: bool
    margin_m: float
    structures: tuple[str, ...] = field(default_factory=tuple)


def check_constraint(
    reflectors_xy_m: np.ndarray, type_index: np.ndarray, tolerance_m: float
) -> ConstraintReport:
    """Check a layout for systematic ambiguities (see the module docstring)."""
    xy = np.asarray(reflectors_xy_m, dtype=float)[:, :2]
    t = np.asarray(type_index, dtype=int).reshape(-1)
    structures: list[str] = []
    for i, j in same_type_pairs(t):
        others = [k for k in range(len(t)) if k not in (i, j)]
        if not others:
            structures.append(f"pair ({i},{j}): every position has 3 mirror images")
        elif len(others) == 1:
            structures.append(
                f"pair ({i},{j}): ambiguity line through its midpoint, orthogonal to the "
                f"line to reflector {others[0]}"
            )
    for (i, j), (k, n), bisector in constraint_checks(t):
        mid = (xy[i] + xy[j]) / 2.0
        q_mid = (xy[k] + xy[n]) / 2.0
        q_dir = xy[n] - xy[k]
        axes = [("line", q_dir)]
        if bisector:
            axes.append(("bisector", np.array([-q_dir[1], q_dir[0]])))
        for name, direction in axes:
            dist = float(_line_distance(mid, q_mid, direction))
            if dist <= tolerance_m:
                structures.append(
                    f"pair ({i},{j}): midpoint {dist:.3f} m from the {name} of pair ({k},{n})"
                    " -> ambiguity line"
                )
    margin = float(constraint_margins(xy, t))
    return ConstraintReport(ok=not structures, margin_m=margin, structures=tuple(structures))
