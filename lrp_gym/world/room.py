"""Room geometry: an axis-aligned box with box-shaped obstacles and reflective surfaces."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Box:
    """Axis-aligned box, corners ``min_m`` and ``max_m`` in metres (shape (3,))."""

    min_m: np.ndarray
    max_m: np.ndarray

    def __post_init__(self) -> None:
        object.__setattr__(self, "min_m", np.asarray(self.min_m, dtype=float))
        object.__setattr__(self, "max_m", np.asarray(self.max_m, dtype=float))

    def contains(self, points: np.ndarray, margin_m: float = 0.0) -> np.ndarray:
        """Whether each point (..., 3) or (..., 2) lies inside the box grown by ``margin_m``."""
        points = np.asarray(points, dtype=float)
        d = points.shape[-1]
        lo, hi = self.min_m[:d] - margin_m, self.max_m[:d] + margin_m
        return np.all((points >= lo) & (points <= hi), axis=-1)


@dataclass(frozen=True)
class Surfaces:
    """Amplitude reflection coefficients |Gamma| (0..1) of the room's surfaces.

    No defaults here: the values come from the validated ``room.surfaces`` of a scenario
    (:class:`lrp_gym.config.SurfacesConfig` holds the defaults and why they were chosen).
    """

    walls: float
    floor: float
    ceiling: float
    obstacles: float

    def face_coefficients(self) -> np.ndarray:
        """Coefficients of the six room faces, ordered x=0, x=Lx, y=0, y=Ly, z=0, z=Lz."""
        return np.array([self.walls, self.walls, self.walls, self.walls, self.floor, self.ceiling])


@dataclass(frozen=True)
class Room:
    """Shoebox room ``[0, Lx] x [0, Ly] x [0, Lz]`` with obstacles.

    Parameters
    ----------
    size_m : array of shape (3,)
        Room extent (Lx, Ly, Lz) in metres.
    obstacles : tuple of Box
        Axis-aligned obstacles; they block the robot and radar paths and reflect.
    surfaces : Surfaces, optional
        Reflection coefficients; None for a room used only for its geometry (free-space and
        path checks), which the radar channel refuses.
    """

    size_m: np.ndarray
    obstacles: tuple[Box, ...] = ()
    surfaces: Surfaces | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "size_m", np.asarray(self.size_m, dtype=float))
        object.__setattr__(self, "obstacles", tuple(self.obstacles))

    @property
    def diagonal_m(self) -> float:
        """Length of the room's space diagonal in metres."""
        return float(np.linalg.norm(self.size_m))

    @property
    def obstacle_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Obstacle corners stacked as two arrays of shape (n_obstacles, 3)."""
        if not self.obstacles:
            empty = np.zeros((0, 3))
            return empty, empty
        return (
            np.stack([b.min_m for b in self.obstacles]),
            np.stack([b.max_m for b in self.obstacles]),
        )

    def inside(self, points: np.ndarray, margin_m: float = 0.0) -> np.ndarray:
        """Whether points (..., 2|3) lie inside the room, at least ``margin_m`` from its walls."""
        points = np.asarray(points, dtype=float)
        d = points.shape[-1]
        return np.all((points >= margin_m) & (points <= self.size_m[:d] - margin_m), axis=-1)

    def free(self, xy: np.ndarray, clearance_m: float = 0.0) -> np.ndarray:
        """Whether floor positions (..., 2) are free for a robot disc of radius ``clearance_m``.

        Only 2-D points are accepted: poses (..., 3) must be sliced to ``[..., :2]`` by the
        caller, since their heading would otherwise be compared with the room's height. A position is free when it is inside the room at least ``clearance_m`` from each wall
        and at least ``clearance_m`` from every obstacle's footprint (obstacles of any height
        block the robot).
        """
        xy = np.asarray(xy, dtype=float)
        if xy.ndim == 0 or xy.shape[-1] != 2:
            # A pose (x, y, theta) is not a floor position: pass ``poses[..., :2]``.
            raise ValueError(f"Room.free expects floor positions of shape (..., 2), got {xy.shape}")
        ok = self.inside(xy, clearance_m)
        if self.obstacles:
            lo, hi = self.obstacle_bounds
            p = xy[..., None, :]
            # Distance from each point to each obstacle footprint (0 inside it).
            gap = np.maximum(np.maximum(lo[:, :2] - p, p - hi[:, :2]), 0.0)
            blocked = np.linalg.norm(gap, axis=-1) <= clearance_m
            ok &= ~np.any(blocked, axis=-1)
        return ok

    def path_free(self, waypoints_xy: np.ndarray, clearance_m: float = 0.0) -> np.ndarray:
        """Whether each leg of a polyline keeps a robot disc of radius ``clearance_m`` free.

        Parameters
        ----------
        waypoints_xy : array of shape (K, 2)
            Floor waypoints in metres.
        clearance_m : float
            Robot radius: a leg is free when every point on it is :meth:`free`.

        Returns
        -------
        ndarray of bool, shape (K - 1,)
        """
        wp = np.asarray(waypoints_xy, dtype=float).reshape(-1, 2)
        return self.legs_free(wp[:-1], wp[1:], clearance_m)

    def legs_free(self, a: np.ndarray, b: np.ndarray, clearance_m: float = 0.0) -> np.ndarray:
        """Whether floor segments a-b (N, 2) keep a disc of radius ``clearance_m`` free; (N,)."""
        a = np.asarray(a, dtype=float).reshape(-1, 2)
        b = np.asarray(b, dtype=float).reshape(-1, 2)
        # The room is convex: a leg inside it (with margin) iff both ends are.
        ok = self.inside(a, clearance_m) & self.inside(b, clearance_m)
        for box in self.obstacles:
            ok &= segment_box_distance_m(a, b, box.min_m[:2], box.max_m[:2]) > clearance_m
        return ok

    def segments_blocked(self, start: np.ndarray, end: np.ndarray) -> np.ndarray:
        """Whether straight segments cross any obstacle (slab test, vectorised).

        Parameters
        ----------
        start, end : arrays of shape (..., 3)
            Segment end points in metres.

        Returns
        -------
        ndarray of bool, shape (...)
            True where the open segment passes through the interior of an obstacle.
        """
        start = np.asarray(start, dtype=float)
        end = np.asarray(end, dtype=float)
        out = np.zeros(np.broadcast_shapes(start.shape, end.shape)[:-1], dtype=bool)
        if not self.obstacles:
            return out
        lo, hi = self.obstacle_bounds  # (B, 3)
        s = start[..., None, :]
        d = (end - start)[..., None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / d
            t0 = (lo - s) * inv
            t1 = (hi - s) * inv
        tmin = np.where(np.isnan(t0), -np.inf, np.minimum(t0, t1))
        tmax = np.where(np.isnan(t1), np.inf, np.maximum(t0, t1))
        # Parallel to a slab and outside it: never enters.
        parallel_out = (d == 0.0) & ((s < lo) | (s > hi))
        t_enter = np.max(tmin, axis=-1)
        t_exit = np.min(tmax, axis=-1)
        eps = 1e-9
        hit = (t_enter < t_exit - eps) & (t_exit > eps) & (t_enter < 1.0 - eps)
        hit &= ~np.any(parallel_out, axis=-1)
        return np.any(hit, axis=-1)


def _point_segment_distance_m(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from points p to segments a-b, all (..., 2)."""
    ab = b - a
    t = np.einsum("...i,...i->...", p - a, ab) / np.maximum(
        np.einsum("...i,...i->...", ab, ab), 1e-24
    )
    closest = a + np.clip(t, 0.0, 1.0)[..., None] * ab
    return np.linalg.norm(p - closest, axis=-1)


def segment_box_distance_m(
    a: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> np.ndarray:
    """Distance from floor segments a-b (N, 2) to the rectangle [lo, hi] (0 where they meet).

    Two disjoint convex sets in the plane are closest at a vertex of one of them, so the
    distance is the smallest of the segment ends to the rectangle and the corners to the segment.
    """
    a = np.asarray(a, dtype=float).reshape(-1, 2)
    b = np.asarray(b, dtype=float).reshape(-1, 2)
    ends = np.stack([a, b], axis=1)  # (N, 2, 2)
    gap = np.maximum(np.maximum(lo - ends, ends - hi), 0.0)
    d = np.min(np.linalg.norm(gap, axis=-1), axis=1)
    corners = np.array([[lo[0], lo[1]], [lo[0], hi[1]], [hi[0], lo[1]], [hi[0], hi[1]]])
    dc = _point_segment_distance_m(corners[None], a[:, None], b[:, None])  # (N, 4)
    d = np.minimum(d, dc.min(axis=1))
    # Slab test: the segment crosses the rectangle (possibly with both ends outside).
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / (b - a)
        t0, t1 = (lo - a) * inv, (hi - a) * inv
    tmin = np.where(np.isnan(t0), -np.inf, np.minimum(t0, t1))
    tmax = np.where(np.isnan(t1), np.inf, np.maximum(t0, t1))
    parallel_out = ((b - a) == 0.0) & ((a < lo) | (a > hi))
    hit = (tmin.max(axis=1) <= tmax.min(axis=1)) & (tmax.min(axis=1) >= 0.0)
    hit &= (tmin.max(axis=1) <= 1.0) & ~parallel_out.any(axis=1)
    return np.where(hit, 0.0, d)
