"""The shoebox image lattice: image indices, image positions, bounce coefficients, and the
planes an unfolded path crosses (the image-source method's geometry, pose-free)."""

from __future__ import annotations

import numpy as np


def lattice_indices(order: int, dims: int = 3) -> np.ndarray:
    """Image indices ``n`` (rows of shape (dims,)) with ``1 <= sum |n_i| <= order``.

    Sorted by order; the count per order in 3-D is 6 for order 1 and 18 for order 2
    (the shoebox lattice of pyroomacoustics).
    """
    r = np.arange(-order, order + 1)
    grid = np.stack(np.meshgrid(*([r] * dims), indexing="ij"), axis=-1).reshape(-1, dims)
    o = np.abs(grid).sum(axis=1)
    keep = (o >= 1) & (o <= order)
    grid, o = grid[keep], o[keep]
    return grid[np.argsort(o, kind="stable")]


def image_positions(points: np.ndarray, indices: np.ndarray, size_m: np.ndarray) -> np.ndarray:
    """Images (..., I, 3) of points (..., 3) for lattice indices (I, 3) in a box ``[0, L]``.

    Along each axis the image for index ``n`` is ``n L + p`` (n even) or ``(n + 1) L - p``
    (n odd): ``n = -1`` mirrors in the face at 0, ``n = 1`` in the face at ``L``.
    """
    p = np.asarray(points, float)[..., None, :]
    n = indices
    odd = (n % 2) != 0
    return np.where(odd, (n + 1) * size_m - p, n * size_m + p)


def lattice_gamma(indices: np.ndarray, face_gamma: np.ndarray) -> np.ndarray:
    """Product of the amplitude reflection coefficients along each image's bounces.

    ``face_gamma`` is ordered x=0, x=L, y=0, y=L, z=0, z=L. A positive index ``n`` on an axis
    bounces ``ceil(n/2)`` times on the face at L and ``floor(n/2)`` times on the face at 0;
    a negative index the other way round.
    """
    a = np.abs(indices)
    first = (a + 1) // 2
    second = a // 2
    pos = indices > 0
    hits_hi = np.where(pos, first, second)
    hits_lo = np.where(pos, second, first)
    lo = face_gamma[0::2]
    hi = face_gamma[1::2]
    return np.prod(lo**hits_lo * hi**hits_hi, axis=-1)


def crossing_planes(indices: np.ndarray, size_m: np.ndarray, order: int):
    """Planes crossed by the unfolded line from cell 0 to cell ``n``: axis, coordinate, valid.

    Shapes (I, K); invalid entries are padding.
    """
    n_img = len(indices)
    axis = np.zeros((n_img, max(order, 1)), dtype=int)
    coord = np.zeros((n_img, max(order, 1)))
    valid = np.zeros((n_img, max(order, 1)), dtype=bool)
    for i, n in enumerate(indices):
        j = 0
        for ax in range(3):
            ks = range(1, n[ax] + 1) if n[ax] > 0 else range(0, n[ax], -1)
            for k in ks:
                axis[i, j], coord[i, j], valid[i, j] = ax, k * size_m[ax], True
                j += 1
    return axis, coord, valid


def fold(x: np.ndarray, size_m: np.ndarray) -> np.ndarray:
    """Fold unfolded (lattice) coordinates back into the room."""
    y = np.mod(x, 2.0 * size_m)
    return np.where(y > size_m, 2.0 * size_m - y, y)
