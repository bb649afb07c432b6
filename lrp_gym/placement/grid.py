"""The grid of robot positions on which layouts are analysed."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lrp_gym.world.room import Room


@dataclass(frozen=True)
class PositionGrid:
    """Cell centres of a regular floor grid, restricted to the free space of a room.

    Attributes
    ----------
    xy_m : ndarray, shape (N, 2)
        Centres of the usable cells (inside the room, ``clearance_m`` from walls and obstacle
        footprints), in metres.
    index : ndarray of int, shape (N, 2)
        Column (x) and row (y) of each usable cell.
    shape : tuple of int
        ``(nx, ny)`` cells of the full grid.
    grid_m : float
        Cell size in metres.
    origin_m : ndarray, shape (2,)
        Centre of cell (0, 0).
    """

    xy_m: np.ndarray
    index: np.ndarray
    shape: tuple[int, int]
    grid_m: float
    origin_m: np.ndarray

    @classmethod
    def from_room(cls, room: Room, grid_m: float, clearance_m: float = 0.0) -> PositionGrid:
        """Cells of size ``grid_m`` covering the room floor, centred in it; free cells only."""
        size = np.asarray(room.size_m[:2], dtype=float)
        n = np.maximum(np.floor(size / grid_m + 1e-9).astype(int), 1)
        origin = (size - n * grid_m) / 2.0 + grid_m / 2.0
        ix, iy = np.meshgrid(np.arange(n[0]), np.arange(n[1]), indexing="ij")
        index = np.stack([ix.ravel(), iy.ravel()], axis=1)
        xy = origin + index * grid_m
        keep = room.free(xy, clearance_m)
        return cls(xy[keep], index[keep], (int(n[0]), int(n[1])), float(grid_m), origin)

    def __len__(self) -> int:
        return len(self.xy_m)

    def to_image(self, values: np.ndarray, fill: float = np.nan) -> np.ndarray:
        """Per-cell ``values`` (N,) as an image of shape (ny, nx) (row = y), ``fill`` elsewhere."""
        values = np.asarray(values)
        dtype = np.result_type(values.dtype, np.asarray(fill).dtype)
        img = np.full((self.shape[1], self.shape[0]), fill, dtype=dtype)
        img[self.index[:, 1], self.index[:, 0]] = values
        return img

    def extent(self) -> tuple[float, float, float, float]:
        """``(x0, x1, y0, y1)`` of the full grid's outer cell edges (for ``imshow``)."""
        h = self.grid_m / 2.0
        x0, y0 = self.origin_m - h
        return (
            float(x0),
            float(x0 + self.shape[0] * self.grid_m),
            float(y0),
            float(y0 + self.shape[1] * self.grid_m),
        )

    def neighbour_pairs(self) -> np.ndarray:
        """Pairs (K, 2) of row indices of usable cells that share an edge."""
        lookup = np.full(self.shape, -1, dtype=np.int64)
        lookup[self.index[:, 0], self.index[:, 1]] = np.arange(len(self))
        right = lookup[:-1, :], lookup[1:, :]
        up = lookup[:, :-1], lookup[:, 1:]
        a = np.concatenate([right[0].ravel(), up[0].ravel()])
        b = np.concatenate([right[1].ravel(), up[1].ravel()])
        ok = (a >= 0) & (b >= 0)
        return np.stack([a[ok], b[ok]], axis=1)
