"""Ambiguity analysis of a reflector layout on a grid of robot positions.

Definitions (documented choices):

- Two fingerprints *agree* when the largest absolute difference of their rows (per type
  sorted distances, see :mod:`lrp_gym.placement.fingerprint`) is at most the tolerance: the
  Chebyshev distance, i.e. the bottleneck matching of the unordered distance sets. A radar that
  resolves distances to ``tolerance_m`` cannot tell such positions apart in any distance.
- Two grid positions are an *ambiguous pair* when they agree and lie more than
  ``separation_m`` apart on the floor (closer ones are the same place for navigation).
- A pair (p, q) is *systematic* when some same-type reflector pair keeps its two labelled
  distances (kept or swapped) within the tolerance, i.e. q sits at one of the images of p
  under that pair's symmetries (:func:`lrp_gym.placement.symmetry.pair_images`), blurred by
  the tolerance; otherwise it is *random* (see :func:`systematic_pairs`). With 2 + 2 types
  every ambiguity is systematic by this definition, as the paper argues.
- A cell is ambiguous when it has an ambiguous partner; it counts as systematic when at least
  one partner is systematic (the symmetry explains it) and as random otherwise, so
  ``ambiguous = systematic + random``.
- *Groups* are connected components of the graph whose edges are the ambiguous pairs and the
  grid neighbours that are both ambiguous: a group is a set of areas sharing fingerprints.

All pairs are found with one Chebyshev ``cKDTree.query_pairs`` over the fingerprints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from lrp_gym.placement.fingerprint import fingerprints, unique_fingerprints
from lrp_gym.placement.grid import PositionGrid
from lrp_gym.placement.symmetry import ConstraintReport, check_constraint, same_type_pairs


def ambiguous_pairs(
    fp: np.ndarray, xy_m: np.ndarray, tolerance_m: float, separation_m: float
) -> np.ndarray:
    """Index pairs (K, 2), i < j, of positions whose fingerprints agree but which lie apart.

    Parameters
    ----------
    fp : ndarray, shape (N, M)
        Fingerprints.
    xy_m : ndarray, shape (N, 2)
        Positions in metres.
    tolerance_m : float
        Largest allowed absolute distance difference (Chebyshev radius, inclusive).
    separation_m : float
        Pairs closer than or at this floor distance are not ambiguous.
    """
    pairs = cKDTree(fp).query_pairs(tolerance_m, p=np.inf, output_type="ndarray")
    if len(pairs) == 0:
        return pairs.reshape(0, 2).astype(np.int64)
    d = xy_m[pairs[:, 0]] - xy_m[pairs[:, 1]]
    far = np.einsum("ij,ij->i", d, d) > separation_m**2
    return pairs[far]


def ambiguous_pairs_bruteforce(
    fp: np.ndarray, xy_m: np.ndarray, tolerance_m: float, separation_m: float
) -> np.ndarray:
    """Same result as :func:`ambiguous_pairs` by comparing all pairs (O(N^2) memory; tests)."""
    cheb = np.max(np.abs(fp[:, None, :] - fp[None, :, :]), axis=-1)
    sep = np.linalg.norm(xy_m[:, None, :] - xy_m[None, :, :], axis=-1)
    i, j = np.nonzero(np.triu((cheb <= tolerance_m) & (sep > separation_m), k=1))
    return np.stack([i, j], axis=1).astype(np.int64)


def ambiguous_mask(n: int, pairs: np.ndarray) -> np.ndarray:
    """Cells (n,) that belong to at least one pair."""
    mask = np.zeros(n, dtype=bool)
    mask[pairs.ravel()] = True
    return mask


def systematic_pairs(
    pairs: np.ndarray, distances_m: np.ndarray, type_index: np.ndarray, tolerance_m: float
) -> np.ndarray:
    """Whether each ambiguous pair (p, q) is explained by a same-type pair symmetry, (K,) bool.

    True when for some same-type reflectors i, j the *labelled* distances agree within the
    tolerance, kept (``d_i(q) ~ d_i(p)``, ``d_j(q) ~ d_j(p)``) or swapped (``d_i(q) ~ d_j(p)``,
    ``d_j(q) ~ d_i(p)``): q then lies at (the tolerance blur of) one of the images of p under
    the pair's symmetries, since two labelled distances fix a position up to the mirror in the
    pair's line. A random ambiguity matches the distance sets only through a relabelling that
    maps no same-type pair onto itself (a 3- or 4-cycle of one type's reflectors).

    Parameters
    ----------
    pairs : ndarray of int, shape (K, 2)
    distances_m : ndarray, shape (N, M)
        Unsorted (labelled) distances of every cell to every reflector.
    type_index : ndarray of int, shape (M,)
    tolerance_m : float
    """
    out = np.zeros(len(pairs), dtype=bool)
    if len(pairs) == 0:
        return out
    dp = distances_m[pairs[:, 0]]
    dq = distances_m[pairs[:, 1]]
    for i, j in same_type_pairs(type_index):  # at most M (M - 1) / 2 pairs: a short loop
        kept = (np.abs(dq[:, i] - dp[:, i]) <= tolerance_m) & (
            np.abs(dq[:, j] - dp[:, j]) <= tolerance_m
        )
        swapped = (np.abs(dq[:, i] - dp[:, j]) <= tolerance_m) & (
            np.abs(dq[:, j] - dp[:, i]) <= tolerance_m
        )
        out |= kept | swapped
    return out


@dataclass(frozen=True)
class AmbiguityResult:
    """Outcome of :func:`analyse_layout`.

    Attributes
    ----------
    grid : PositionGrid
    ambiguous, systematic, random : ndarray of bool, shape (N,)
        Cell classes (``systematic | random == ambiguous``, disjoint).
    group : ndarray of int, shape (N,)
        Ambiguity group of each ambiguous cell (0 = largest), -1 for unique cells.
    n_pairs : int
        Number of ambiguous pairs.
    constraint : ConstraintReport
    unique_fingerprints : int
        Distinct fingerprints quantised at the look-up-table resolution over the grid.
    tolerance_m, separation_m : float
    """

    grid: PositionGrid
    ambiguous: np.ndarray
    systematic: np.ndarray
    random: np.ndarray
    group: np.ndarray
    n_pairs: int
    constraint: ConstraintReport
    unique_fingerprints: int
    tolerance_m: float
    separation_m: float

    @property
    def ambiguous_fraction(self) -> float:
        return float(self.ambiguous.mean()) if len(self.ambiguous) else 0.0

    @property
    def systematic_fraction(self) -> float:
        return float(self.systematic.mean()) if len(self.systematic) else 0.0

    @property
    def random_fraction(self) -> float:
        return float(self.random.mean()) if len(self.random) else 0.0

    @property
    def n_groups(self) -> int:
        return int(self.group.max() + 1) if len(self.group) else 0

    def summary(self) -> dict:
        """The figures as a JSON-ready mapping."""
        return {
            "ambiguous_fraction": self.ambiguous_fraction,
            "systematic_fraction": self.systematic_fraction,
            "random_fraction": self.random_fraction,
            "unique_fingerprints": self.unique_fingerprints,
            "constraint_ok": self.constraint.ok,
            "constraint_margin_m": self.constraint.margin_m,
            "constraint_structures": list(self.constraint.structures),
            "ambiguity_groups": self.n_groups,
            "ambiguous_pairs": self.n_pairs,
            "cells": len(self.grid),
            "grid_m": self.grid.grid_m,
            "tolerance_m": self.tolerance_m,
            "separation_m": self.separation_m,
        }


def ambiguity_groups(grid: PositionGrid, pairs: np.ndarray, ambiguous: np.ndarray) -> np.ndarray:
    """Group label per cell (-1 = unique); groups numbered by decreasing size."""
    n = len(grid)
    nb = grid.neighbour_pairs()
    nb = nb[ambiguous[nb[:, 0]] & ambiguous[nb[:, 1]]]
    edges = np.concatenate([pairs.reshape(-1, 2), nb])
    graph = coo_matrix(
        (np.ones(len(edges), dtype=np.int8), (edges[:, 0], edges[:, 1])), shape=(n, n)
    )
    _, labels = connected_components(graph, directed=False)
    labels = np.where(ambiguous, labels, -1)
    out = np.full(n, -1, dtype=np.int64)
    if ambiguous.any():
        ids, counts = np.unique(labels[ambiguous], return_counts=True)
        rank = np.empty(ids.max() + 1, dtype=np.int64)
        rank[ids[np.argsort(-counts, kind="stable")]] = np.arange(len(ids))
        out[ambiguous] = rank[labels[ambiguous]]
    return out


def analyse_layout(
    reflectors_m: np.ndarray,
    type_index: np.ndarray,
    grid: PositionGrid,
    mount_height_m: float,
    tolerance_m: float,
    separation_m: float,
    *,
    lut_resolution_m: float = 0.075,
    constraint_tolerance_m: float = 0.1,
) -> AmbiguityResult:
    """Ambiguity map of a layout (see the module docstring for the definitions).

    Parameters
    ----------
    reflectors_m : ndarray, shape (M, 3)
    type_index : ndarray of int, shape (M,)
    grid : PositionGrid
        Robot positions to analyse.
    mount_height_m, tolerance_m, separation_m : float
    lut_resolution_m : float
        Quantisation for :func:`unique_fingerprints`.
    constraint_tolerance_m : float
        Tolerance of the layout constraint check.
    """
    reflectors_m = np.asarray(reflectors_m, dtype=float).reshape(-1, 3)
    fp = fingerprints(grid.xy_m, reflectors_m, type_index, mount_height_m)
    pairs = ambiguous_pairs(fp, grid.xy_m, tolerance_m, separation_m)
    labelled = fingerprints(grid.xy_m, reflectors_m, np.arange(len(reflectors_m)), mount_height_m)
    sys_pair = systematic_pairs(pairs, labelled, type_index, tolerance_m)
    ambiguous = ambiguous_mask(len(grid), pairs)
    systematic = ambiguous_mask(len(grid), pairs[sys_pair])
    return AmbiguityResult(
        grid=grid,
        ambiguous=ambiguous,
        systematic=systematic,
        random=ambiguous & ~systematic,
        group=ambiguity_groups(grid, pairs, ambiguous),
        n_pairs=len(pairs),
        constraint=check_constraint(reflectors_m[:, :2], type_index, constraint_tolerance_m),
        unique_fingerprints=unique_fingerprints(fp, lut_resolution_m),
        tolerance_m=float(tolerance_m),
        separation_m=float(separation_m),
    )


def ambiguous_fraction(
    reflectors_m: np.ndarray,
    type_index: np.ndarray,
    grid: PositionGrid,
    mount_height_m: float,
    tolerance_m: float,
    separation_m: float,
) -> float:
    """Only the ambiguous area fraction (the layout search's score; no classification)."""
    fp = fingerprints(grid.xy_m, reflectors_m, type_index, mount_height_m)
    pairs = ambiguous_pairs(fp, grid.xy_m, tolerance_m, separation_m)
    return float(ambiguous_mask(len(grid), pairs).mean()) if len(grid) else 0.0
