"""Cross-field checks of a scenario: what each section can only be judged against the others.

Every problem is one message that starts with the field to change. They are the conditions
under which the runtime chain (radar, tracker, AMCL, env, evaluator) would otherwise fail or
produce physically meaningless numbers: a robot that does not fit where it is asked to drive,
a path through an obstacle, a goal task that cannot be sampled, a range window shorter than
the room, a reflector without an orientation.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np

from lrp_gym.config.base import _fmt
from lrp_gym.world.room import Box, Room

if TYPE_CHECKING:
    from lrp_gym.config import ScenarioConfig

#: Grid step (m) of the free-space check; positions closer than this to a blocked cell may
#: be missed, which only matters for strips of free space narrower than a grid step.
FREE_GRID_M = 0.05
#: Extra clearance the env keeps when it samples goal-task start and goal positions.
GOAL_MARGIN_M = 0.1


def cross_problems(cfg: ScenarioConfig) -> Iterator[str]:
    """Yield one ``field: message`` per cross-field problem of ``cfg``."""
    room = Room(
        np.asarray(cfg.room.size, dtype=float),
        tuple(Box(b.min, b.max) for b in cfg.room.obstacles),
    )
    yield from _room_problems(cfg)
    yield from _reflector_problems(cfg, room)
    yield from _radar_problems(cfg)
    yield from _robot_problems(cfg, room)
    yield from _task_problems(cfg, room)
    loc = cfg.localization
    if loc.initial_particles < loc.min_particles:
        yield (
            f"localization.initial_particles: {loc.initial_particles} is below "
            f"localization.min_particles ({loc.min_particles})"
        )


def _room_problems(cfg: ScenarioConfig) -> Iterator[str]:
    size = np.asarray(cfg.room.size)
    for i, b in enumerate(cfg.room.obstacles):
        if np.any(np.asarray(b.min) < 0) or np.any(np.asarray(b.max) > size):
            yield (
                f"room.obstacles[{i}]: box {_fmt(b.min)}..{_fmt(b.max)} is not inside the room "
                f"{_fmt(cfg.room.size)}"
            )


def _reflector_problems(cfg: ScenarioConfig, room) -> Iterator[str]:
    size = np.asarray(cfg.room.size)
    if not cfg.reflectors.layout:
        yield "reflectors.layout: at least one reflector is needed"
    # The default boresight points at the room centre at radar height (lrp_gym.world.World).
    centre = np.array([size[0] / 2, size[1] / 2, cfg.radar.mount_height_m])
    for i, r in enumerate(cfg.reflectors.layout):
        p = np.asarray(r.position)
        if np.any(p < 0) or np.any(p > size):
            yield f"reflectors.layout[{i}].position: {_fmt(r.position)} is outside the room {_fmt(cfg.room.size)}"
        elif any(bool(b.contains(p)) for b in room.obstacles):
            yield f"reflectors.layout[{i}].position: {_fmt(r.position)} is inside an obstacle"
        if r.axis is not None and np.linalg.norm(r.axis) == 0:
            yield f"reflectors.layout[{i}].axis: must not be the zero vector"
        elif r.axis is None and np.linalg.norm(centre - p) < 1e-9:
            yield (
                f"reflectors.layout[{i}].axis: the reflector sits where its default axis points "
                f"(the room centre at the radar height {_fmt(cfg.radar.mount_height_m)} m), "
                "so it has no orientation; give an axis"
            )


def _radar_problems(cfg: ScenarioConfig) -> Iterator[str]:
    size = np.asarray(cfg.room.size)
    if cfg.radar.mount_height_m >= size[2]:
        yield f"radar.mount_height_m: {_fmt(cfg.radar.mount_height_m)} is not below the ceiling at {_fmt(size[2])}"
    fm = cfg.radar.fmcw()
    diag = float(np.linalg.norm(size))
    if fm.max_range_m < diag:
        yield (
            f"radar: maximum range {fm.max_range_m:.3f} m does not cover the room diagonal "
            f"{diag:.3f} m (raise samples_per_chirp or lower bandwidth_hz)"
        )
    req = cfg.radar.requirements
    if req is not None and fm.range_resolution_m > req.range_resolution_m * (1 + 1e-9):
        yield "radar.requirements.range_resolution_m: not met by the waveform"
    max_speed = cfg.robot.max_speed_mps
    if fm.max_velocity_mps < max_speed:
        yield (
            f"radar: unambiguous velocity {fm.max_velocity_mps:.3f} m/s is below robot.max_speed_mps "
            f"{_fmt(max_speed)} (raise chirps or shorten chirp_period_s)"
        )
    if cfg.task.frame_period_s < fm.frame_time_s:
        yield (
            f"task.frame_period_s: {_fmt(cfg.task.frame_period_s)} s is shorter than one radar "
            f"frame ({fm.frame_time_s:.4g} s = chirps_per_frame x chirp_period_s)"
        )


def _robot_problems(cfg: ScenarioConfig, room) -> Iterator[str]:
    radius = cfg.robot.radius_m
    size = np.asarray(cfg.room.size)
    if 2 * radius >= min(size[:2]):
        yield f"robot.radius_m: {_fmt(radius)} does not fit in the room {_fmt(cfg.room.size)}"
        return
    if not free_grid(room, radius).size:
        yield (
            f"robot.radius_m: a robot of radius {_fmt(radius)} m fits nowhere in the room "
            "between the walls and room.obstacles"
        )
        return
    sx, sy, _ = cfg.robot.start_pose
    if not bool(room.free(np.array([sx, sy]), radius)):
        yield (
            f"robot.start_pose: the robot (robot.radius_m {_fmt(radius)} m) at {_fmt([sx, sy])} "
            "overlaps a wall or an obstacle (or is outside the room)"
        )
    # Collisions are checked env.substeps times per frame: between two checks the robot must
    # not move farther than its own diameter, or it can jump through a wall or a thin box.
    step_m = cfg.robot.max_speed_mps * cfg.task.frame_period_s / cfg.env.substeps
    if step_m > 2.0 * radius:
        yield (
            f"task.frame_period_s: at robot.max_speed_mps the robot moves {step_m:.3g} m between "
            f"collision checks, more than its diameter {_fmt(2 * radius)} m (lower "
            "frame_period_s or raise env.substeps)"
        )


def _task_problems(cfg: ScenarioConfig, room) -> Iterator[str]:
    task = cfg.task
    radius = cfg.robot.radius_m
    path = np.asarray(task.path, dtype=float).reshape(-1, 2)
    blocked = np.flatnonzero(~room.free(path, radius))
    for i in blocked[:3]:
        yield (
            f"task.path[{i}]: the robot (robot.radius_m {_fmt(radius)} m) at waypoint "
            f"{_fmt(list(path[i]))} overlaps a wall or an obstacle (or is outside the room)"
        )
    if len(blocked) > 3:
        yield f"task.path: {len(blocked) - 3} more waypoints overlap a wall or an obstacle"
    if len(path) and len(np.unique(path, axis=0)) < 2:
        yield "task.path: needs at least two distinct waypoints"
    elif len(path) >= 2:
        ends_free = room.free(path, radius)
        legs = room.path_free(path, radius)
        for i in np.flatnonzero(~legs & ends_free[:-1] & ends_free[1:]):
            yield (
                f"task.path[{i}]..[{i + 1}]: the leg {_fmt(list(path[i]))} -> "
                f"{_fmt(list(path[i + 1]))} passes within robot.radius_m ({_fmt(radius)} m) "
                "of an obstacle"
            )
    if task.laps > 1 and len(path) >= 2 and not task.closed:
        yield (
            f"task.laps: {task.laps} laps need a closed task.path (its last waypoint "
            f"{_fmt(list(path[-1]))} equal to its first {_fmt(list(path[0]))})"
        )
    g = task.goal
    if g.min_distance_m >= g.max_distance_m:
        yield (
            f"task.goal.min_distance_m: {_fmt(g.min_distance_m)} must be below "
            f"task.goal.max_distance_m {_fmt(g.max_distance_m)}"
        )
    elif task.mode == "goal":
        pts = free_grid(room, radius + GOAL_MARGIN_M)
        span = _max_pairwise_distance_m(pts, g.min_distance_m)
        if span <= g.min_distance_m:
            yield (
                f"task.goal.min_distance_m: {_fmt(g.min_distance_m)} m is not below the largest "
                f"distance between free start and goal positions in the room ({span:.2f} m)"
            )


_MAX_GRID_POINTS = 250_000


def free_grid(room, clearance_m: float, grid_m: float = FREE_GRID_M) -> np.ndarray:
    """Floor grid points (N, 2) where a robot disc of radius ``clearance_m`` is free."""
    size = np.asarray(room.size_m[:2], dtype=float)
    # Coarser in a large room: the check needs the free space's extent, not its detail.
    grid_m = max(grid_m, float(np.sqrt(size[0] * size[1] / _MAX_GRID_POINTS)))
    xs = np.arange(grid_m / 2, size[0], grid_m)
    ys = np.arange(grid_m / 2, size[1], grid_m)
    xy = np.stack(np.meshgrid(xs, ys, indexing="ij"), axis=-1).reshape(-1, 2)
    return xy[room.free(xy, clearance_m)]


def _max_pairwise_distance_m(points: np.ndarray, lower_bound_m: float | None = None) -> float:
    """Largest distance between two of ``points`` (N, 2); 0 for fewer than two.

    With ``lower_bound_m``, a cheaper lower estimate (the larger side of the bounding box) is
    returned as soon as it exceeds that bound.
    """
    if len(points) < 2:
        return 0.0
    if lower_bound_m is not None and np.ptp(points, axis=0).max() > lower_bound_m:
        return float(np.ptp(points, axis=0).max())  # enough to show the span exceeds the bound
    # The farthest pair are vertices of the convex hull.
    from scipy.spatial import ConvexHull, QhullError

    try:
        ext = points[ConvexHull(points).vertices]
    except QhullError:  # collinear or a single point: the extremes of a line
        ext = points[[0, -1]]
    d = np.linalg.norm(ext[:, None] - ext[None], axis=-1)
    return float(d.max())
