"""Task geometry: path projection, upcoming waypoints, sampled goal tasks."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.config import TaskConfig
from lrp_gym.envs.observations import to_robot_frame
from lrp_gym.envs.task import WaypointPath, densify, sample_goal_task
from lrp_gym.world import Box, Room

SQUARE = WaypointPath.from_points(np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0.2]], float))


@pytest.mark.parametrize(
    ("xy", "expected"),
    [((0.5, 0.1), 0.5), ((0.9, 0.5), 1.5), ((0.1, 0.5), 3.5), ((1.3, -0.2), 1.0), ((-1, -1), 0.0)],
)
def test_projection_onto_polyline(xy, expected):
    assert SQUARE.project(np.array(xy, float)) == pytest.approx(expected)


def test_projection_window_prevents_jumps_on_a_loop():
    # (0.1, 0.1) is near both the start and the end of the loop.
    assert SQUARE.project(np.array([0.1, 0.1])) == pytest.approx(0.1)
    assert SQUARE.project(np.array([0.1, 0.1]), s_min=2.5, window_m=3.0) == pytest.approx(3.8)


def test_upcoming_waypoints_repeat_the_goal():
    up = SQUARE.upcoming(3.2, 3)
    assert np.allclose(up, [[0, 0.2], [0, 0.2], [0, 0.2]])
    assert np.allclose(SQUARE.upcoming(0.0, 2), [[1, 0], [1, 1]])


def test_robot_frame_transform():
    pts = to_robot_frame(np.array([[1.0, 1.0]]), np.array([1.0, 0.0, np.pi / 2]))
    assert np.allclose(pts, [[1.0, 0.0]])  # straight ahead when facing +y


def test_densify_spacing():
    pts = densify(np.array([[0.0, 0.0], [1.2, 0.0]]), 0.5)
    assert len(pts) == 4 and np.allclose(np.diff(pts[:, 0]), 0.4)


def test_sampled_goal_tasks_are_free_and_within_distance():
    room = Room(np.array([5.0, 5.0, 4.0]), (Box([2, 2, 0], [3, 3, 1]),))
    task = TaskConfig(mode="goal")
    rng = np.random.default_rng(0)
    for _ in range(30):
        start, path = sample_goal_task(room, task, 0.3, rng)
        dense = np.concatenate([path.point_at(np.linspace(0, path.length_m, 200))])
        assert room.free(dense, 0.3).all()
        d = np.linalg.norm(path.goal_m - start[:2])
        assert task.goal.min_distance_m <= d <= task.goal.max_distance_m
        assert np.all(np.diff(path.arc_m) <= task.goal.waypoint_spacing_m + 1e-9)
