"""Look-up table positioning: quantised fingerprints of a fine grid mapped to cell centroids.

Construction: the free floor (``room.free`` with ``clearance_m``) is sampled on a grid of
``grid_m``; each cell's fingerprint (distances sorted within each type, types concatenated in
the layout's order) is quantised to ``floor(d / resolution_m)``. Every unique quantised
fingerprint is one entry; it maps to the centroid of the cells that share it, with the cells'
spread about it (plus the grid's own ``grid_m^2 / 12``) as position covariance. Where the cells
of one fingerprint form several disconnected regions (an ambiguous fingerprint), the entry maps
to the centroid of its largest region: the centroid of all its cells would lie between the
regions, on no candidate position at all. ``regions_per_entry`` tells which entries are
ambiguous. The entry's key in the
k-d tree is the centre of its quantisation bin, ``(q + 1/2) resolution_m``: an exact
fingerprint lies inside its own bin's cube, whose centre is then its nearest key, so exact
fingerprints return their own entry.

Queries return the entry nearest in Euclidean distance (``scipy.spatial.cKDTree``).

Counts that differ from the layout (policy):

- *more* distances of a type than reflectors (clutter): every subset of the right size is
  tried and the subset with the nearest entry wins;
- *fewer* distances (missed reflectors): the sorted measured distances are matched, in order,
  against every sub-fingerprint of the sorted slots of that type (a k-d tree over those
  columns of the entry keys, built on first use and cached); the nearest match wins;
- both combine across types (product of the per-type options);
- no distance at all: the centroid of the free room with its full spread as covariance.

A table cannot observe heading: the pose's heading is 0 with an infinite variance.
"""

from __future__ import annotations

from itertools import combinations, product

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from lrp_gym.localization.pose_estimate import PoseEstimate
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.world import World


class LookupTable:
    """Fingerprint-to-position table of a world's reflector layout.

    Parameters
    ----------
    world : World
        Room, reflector layout and radar height.
    resolution_m : float
        Quantisation step of the distances (the paper uses the radar's range resolution).
    grid_m : float
        Spacing of the grid of positions the table is built from.
    clearance_m : float
        Only positions at least this far from walls and obstacles are tabulated.

    Attributes
    ----------
    n_entries : int
        Number of unique quantised fingerprints.
    positions_m : ndarray (n_entries, 2)
        Centroid of each entry's cells.
    keys_m : ndarray (n_entries, M)
        Bin-centre fingerprint of each entry (the k-d tree's points).
    cell_counts : ndarray (n_entries,)
        Grid cells per entry.
    regions_per_entry : ndarray (n_entries,)
        Connected regions (4-neighbourhood) the entry's cells form; > 1 means ambiguous.
    n_regions : int
        Total number of connected regions.
    """

    def __init__(
        self,
        world: World,
        resolution_m: float = 0.075,
        grid_m: float = 0.025,
        clearance_m: float = 0.0,
    ) -> None:
        self.resolution_m = float(resolution_m)
        self.grid_m = float(grid_m)
        layout = world.layout
        self.type_names = layout.type_names
        free, xy = _free_cells(world, grid_m, clearance_m)
        fp, self._slices = _type_sorted_fingerprints(world.true_distances_m(xy), layout)
        q = np.floor(fp / self.resolution_m).astype(np.int64)
        uq, inverse, counts = np.unique(q, axis=0, return_inverse=True, return_counts=True)
        inverse = inverse.reshape(-1)
        self.n_entries = int(len(uq))
        self.cell_counts = counts
        region = _regions(free, inverse)
        self.n_regions = int(region.max()) + 1
        self.positions_m, self.regions_per_entry = _entry_positions(
            region, inverse, self.n_entries, xy
        )
        self._cov_xy = _entry_covariances(self.positions_m, inverse, counts, xy, grid_m)
        self.keys_m = (uq + 0.5) * self.resolution_m
        self._trees: dict[tuple[int, ...], cKDTree] = {
            tuple(range(self.keys_m.shape[1])): cKDTree(self.keys_m)
        }
        self._room_mean = xy.mean(axis=0)
        self._room_cov = np.cov(xy.T)
        self.last_residual_m = float("nan")

    def _tree(self, columns: tuple[int, ...]) -> cKDTree:
        tree = self._trees.get(columns)
        if tree is None:
            tree = cKDTree(self.keys_m[:, list(columns)])
            self._trees[columns] = tree
        return tree

    def _options(self, fingerprint: Fingerprint) -> list[tuple[np.ndarray, tuple[int, ...]]]:
        """(query vector, table columns) candidates for the count-mismatch policy."""
        per_type = []
        for t, name in enumerate(self.type_names):
            sl = self._slices[t]
            slots = list(range(sl.start, sl.stop))
            if name in fingerprint.type_names:
                z = np.sort(np.asarray(fingerprint.distances_m[fingerprint.type_names.index(name)]))
            else:
                z = np.zeros(0)
            n, m = len(z), len(slots)
            if n == m:
                opts = [(z, tuple(slots))]
            elif n > m:
                opts = [(z[list(c)], tuple(slots)) for c in combinations(range(n), m)]
            else:
                opts = [(z, tuple(slots[i] for i in c)) for c in combinations(range(m), n)]
            per_type.append(opts)
        out = []
        for combo in product(*per_type):
            cols = tuple(c for _, cs in combo for c in cs)
            vec = np.concatenate([v for v, _ in combo]) if combo else np.zeros(0)
            out.append((vec, cols))
        return out

    def lookup(self, fingerprint: Fingerprint) -> tuple[int, float]:
        """Index of the nearest entry and the Euclidean distance to its key (m); -1 if none."""
        best, best_d = -1, np.inf
        for vec, cols in self._options(fingerprint):
            if not cols:
                continue
            d, i = self._tree(cols).query(vec)
            if d < best_d:
                best, best_d = int(i), float(d)
        return best, best_d

    def query(self, fingerprint: Fingerprint) -> PoseEstimate:
        """Position of the entry nearest to ``fingerprint`` (heading 0, variance infinite)."""
        i, d = self.lookup(fingerprint)
        self.last_residual_m = d
        cov = np.zeros((3, 3))
        cov[2, 2] = np.inf
        if i < 0:
            cov[:2, :2] = self._room_cov
            return PoseEstimate(np.array([*self._room_mean, 0.0]), cov)
        cov[:2, :2] = self._cov_xy[i]
        return PoseEstimate(np.array([*self.positions_m[i], 0.0]), cov)


def _free_cells(world: World, grid_m: float, clearance_m: float) -> tuple[np.ndarray, np.ndarray]:
    """The grid's free mask (nx, ny) and the centres (N, 2) of its free cells."""
    size = world.room.size_m[:2]
    gx = np.arange(grid_m / 2.0, size[0], grid_m)
    gy = np.arange(grid_m / 2.0, size[1], grid_m)
    grid_xy = np.stack(np.meshgrid(gx, gy, indexing="ij"), axis=-1)
    free = world.room.free(grid_xy, clearance_m)
    xy = grid_xy[free]
    if len(xy) == 0:
        raise ValueError("no free grid cell to tabulate")
    return free, xy


def _type_sorted_fingerprints(
    dist_m: np.ndarray, layout: ReflectorLayout
) -> tuple[np.ndarray, list[slice]]:
    """Distances (N, M) regrouped as each type's slots, sorted, in type order; and each type's
    column slice (a reflector's identity within its type is unknown to the radar)."""
    slices: list[slice] = []
    cols = []
    start = 0
    for t in range(len(layout.types)):
        d = np.sort(dist_m[:, layout.type_index == t], axis=1)
        cols.append(d)
        slices.append(slice(start, start + d.shape[1]))
        start += d.shape[1]
    return np.concatenate(cols, axis=1), slices


def _entry_positions(
    region: np.ndarray, inverse: np.ndarray, n_entries: int, xy: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Each entry's position (the centroid of its largest connected region) and region count.

    Parameters
    ----------
    region : ndarray (N,)
        Connected-region label of each free cell.
    inverse : ndarray (N,)
        Table entry of each free cell.
    n_entries : int
    xy : ndarray (N, 2)
        Cell centres.
    """
    n_regions = int(region.max()) + 1
    region_size = np.bincount(region)
    region_entry = np.zeros(n_regions, dtype=np.int64)
    region_entry[region] = inverse
    order = np.lexsort((region_size, region_entry))
    last = np.r_[region_entry[order][1:] != region_entry[order][:-1], True]
    main_region = np.empty(n_entries, dtype=np.int64)
    main_region[region_entry[order][last]] = order[last]
    regions_per_entry = np.bincount(region_entry, minlength=n_entries)
    rx = np.bincount(region, xy[:, 0]) / region_size
    ry = np.bincount(region, xy[:, 1]) / region_size
    return np.column_stack([rx[main_region], ry[main_region]]), regions_per_entry


def _entry_covariances(
    positions_m: np.ndarray, inverse: np.ndarray, counts: np.ndarray, xy: np.ndarray, grid_m: float
) -> np.ndarray:
    """Covariance (n_entries, 2, 2) of all of an entry's cells about its position, plus the
    cell's own quantisation variance: honest when the entry is ambiguous."""
    mx, my = positions_m[:, 0], positions_m[:, 1]
    dx, dy = xy[:, 0] - mx[inverse], xy[:, 1] - my[inverse]
    var_x = np.bincount(inverse, dx * dx) / counts
    var_y = np.bincount(inverse, dy * dy) / counts
    cxy = np.bincount(inverse, dx * dy) / counts
    return (
        np.stack([np.stack([var_x, cxy], -1), np.stack([cxy, var_y], -1)], axis=-2)
        + np.eye(2) * grid_m**2 / 12.0
    )


def _regions(free: np.ndarray, entry: np.ndarray) -> np.ndarray:
    """Connected-region label (4-neighbourhood) of each free cell with the same entry.

    ``free`` is the (nx, ny) mask of tabulated cells, ``entry`` the entry index of each free
    cell in row-major order.
    """
    label = np.full(free.shape, -1, dtype=np.int64)
    label[free] = entry
    index = np.full(free.shape, -1, dtype=np.int64)
    index[free] = np.arange(int(free.sum()))
    rows, cols = [], []
    for a, b in (
        (np.s_[:-1, :], np.s_[1:, :]),
        (np.s_[:, :-1], np.s_[:, 1:]),
    ):
        same = (label[a] == label[b]) & (label[a] >= 0)
        rows.append(index[a][same])
        cols.append(index[b][same])
    r, c = np.concatenate(rows), np.concatenate(cols)
    n = int(free.sum())
    graph = coo_matrix((np.ones(len(r), dtype=np.int8), (r, c)), shape=(n, n))
    return connected_components(graph, directed=False)[1]
