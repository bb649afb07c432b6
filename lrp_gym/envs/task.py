"""Navigation tasks: a waypoint path with arc-length progress, fixed or sampled per episode."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lrp_gym.config import ScenarioError, TaskConfig
from lrp_gym.world import Room


@dataclass(frozen=True)
class WaypointPath:
    """A polyline of waypoints (K, 2) with cumulative arc length.

    Attributes
    ----------
    waypoints_m : ndarray, shape (K, 2)
    arc_m : ndarray, shape (K,)
        Arc length at each waypoint, ``arc_m[0] == 0``.
    """

    waypoints_m: np.ndarray
    arc_m: np.ndarray
    _seg_start: np.ndarray = field(init=False, repr=False, compare=False)
    _seg_dir: np.ndarray = field(init=False, repr=False, compare=False)
    _seg_len: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # Segment geometry, cached: project() runs twice per env step.
        a = self.waypoints_m[:-1]
        ab = self.waypoints_m[1:] - a
        seg_len = np.maximum(np.hypot(ab[:, 0], ab[:, 1]), 1e-12)
        object.__setattr__(self, "_seg_start", a)
        object.__setattr__(self, "_seg_dir", ab / seg_len[:, None])
        object.__setattr__(self, "_seg_len", seg_len)

    @classmethod
    def from_points(cls, points: np.ndarray) -> WaypointPath:
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        return cls(pts, np.concatenate([[0.0], np.cumsum(seg)]))

    @property
    def length_m(self) -> float:
        return float(self.arc_m[-1])

    @property
    def goal_m(self) -> np.ndarray:
        return self.waypoints_m[-1]

    def project(self, xy: np.ndarray, s_min: float = 0.0, window_m: float = np.inf) -> float:
        """Arc length of the point on the path nearest to ``xy``.

        Only the part of the path in ``[s_min, s_min + window_m]`` is searched, so progress
        along a path that passes the same place twice does not jump ahead.
        """
        arc = self.arc_m
        # Segments overlapping the window.
        i0 = max(int(np.searchsorted(arc, s_min, side="right")) - 1, 0)
        i1 = min(int(np.searchsorted(arc, s_min + window_m, side="left")), len(arc) - 1)
        i1 = max(i1, i0 + 1)
        rel = xy - self._seg_start[i0:i1]
        along = np.clip(np.einsum("ij,ij->i", rel, self._seg_dir[i0:i1]), 0.0, self._seg_len[i0:i1])
        s = np.clip(arc[i0:i1] + along, s_min, s_min + window_m)
        # Distance from xy to the point at s on its own segment.
        t = s - arc[i0:i1]
        off = rel - t[:, None] * self._seg_dir[i0:i1]
        return float(s[np.argmin(np.einsum("ij,ij->i", off, off))])

    def point_at(self, s_m: np.ndarray | float) -> np.ndarray:
        """Points (..., 2) at arc lengths ``s_m``."""
        s = np.clip(np.asarray(s_m, dtype=float), 0.0, self.length_m)
        x = np.interp(s, self.arc_m, self.waypoints_m[:, 0])
        y = np.interp(s, self.arc_m, self.waypoints_m[:, 1])
        return np.stack([x, y], axis=-1)

    def upcoming(self, s_m: float, n: int) -> np.ndarray:
        """The next ``n`` waypoints beyond arc length ``s_m`` (the goal repeated at the end)."""
        first = int(np.searchsorted(self.arc_m, s_m + 1e-6, side="right"))
        idx = np.minimum(np.arange(first, first + n), len(self.arc_m) - 1)
        return self.waypoints_m[idx]


def _segment_free(
    room: Room, a: np.ndarray, b: np.ndarray, clearance_m: float, step_m: float
) -> bool:
    n = max(int(np.ceil(np.linalg.norm(b - a) / step_m)), 1)
    pts = a + np.linspace(0.0, 1.0, n + 1)[:, None] * (b - a)
    return bool(np.all(room.free(pts, clearance_m)))


def densify(points: np.ndarray, spacing_m: float) -> np.ndarray:
    """Insert waypoints so consecutive ones are at most ``spacing_m`` apart."""
    out = [points[0]]
    for a, b in zip(points[:-1], points[1:]):
        n = max(int(np.ceil(np.linalg.norm(b - a) / spacing_m)), 1)
        out.extend(a + (b - a) * (k / n) for k in range(1, n + 1))
    return np.asarray(out)


def sample_free_position(
    room: Room, clearance_m: float, rng: np.random.Generator, max_tries: int = 1000
) -> np.ndarray:
    """A uniformly random floor position at least ``clearance_m`` from walls and obstacles."""
    lo, hi = np.full(2, clearance_m), room.size_m[:2] - clearance_m
    for _ in range(max_tries // 64 + 1):
        cand = rng.uniform(lo, hi, size=(64, 2))
        ok = room.free(cand, clearance_m)
        if ok.any():
            return cand[np.argmax(ok)]
    raise ScenarioError(
        [
            f"robot.radius_m: no free position found for a robot of radius {clearance_m:.3g} m "
            "(with margin) between the walls and room.obstacles"
        ]
    )


def sample_goal_task(
    room: Room, task: TaskConfig, clearance_m: float, rng: np.random.Generator
) -> tuple[np.ndarray, WaypointPath]:
    """A random start pose and a short collision-free waypoint path to a random goal.

    The goal lies ``task.goal.min_distance_m`` to ``max_distance_m`` from the start. A straight
    line is used when it is free; otherwise one random via point that frees both legs.
    """
    g = task.goal
    for _ in range(200):
        start = sample_free_position(room, clearance_m, rng)
        goal = sample_free_position(room, clearance_m, rng)
        dist = float(np.linalg.norm(goal - start))
        if not g.min_distance_m <= dist <= g.max_distance_m:
            continue
        corners = [start, goal]
        if not _segment_free(room, start, goal, clearance_m, 0.05):
            via = sample_free_position(room, clearance_m, rng)
            if not (
                _segment_free(room, start, via, clearance_m, 0.05)
                and _segment_free(room, via, goal, clearance_m, 0.05)
            ):
                continue
            corners = [start, via, goal]
        path = WaypointPath.from_points(densify(np.asarray(corners), g.waypoint_spacing_m))
        first = path.waypoints_m[1] - start
        heading = np.arctan2(first[1], first[0]) + rng.uniform(-np.pi / 2, np.pi / 2)
        theta = (heading + np.pi) % (2 * np.pi) - np.pi
        return np.array([start[0], start[1], theta]), path
    raise ScenarioError(
        [
            f"task.goal: no start and goal {g.min_distance_m:g}..{g.max_distance_m:g} m apart "
            "with a free path were found in 200 tries; widen task.goal.min_distance_m / "
            "max_distance_m or free the room (room.obstacles, robot.radius_m)"
        ]
    )
