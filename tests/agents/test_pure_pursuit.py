"""Pure pursuit: lookahead geometry, closed loop on a kinematic robot, speed limits."""

from __future__ import annotations

import numpy as np
import pytest

from agents.pure_pursuit import PurePursuitConfig, PurePursuitPolicy, lookahead_point
from lrp_gym.envs.observations import NavSnapshot, make_observation
from lrp_gym.envs.task import WaypointPath
from lrp_gym.world import integrate_unicycle


def test_lookahead_point_on_straight_line_is_at_the_radius():
    pts = np.array([[1.0, 0.0], [2.0, 0.0]])
    np.testing.assert_allclose(lookahead_point(pts, 0.5), [0.5, 0.0])
    np.testing.assert_allclose(lookahead_point(pts, 1.5), [1.5, 0.0])


def test_lookahead_point_on_corner_lies_on_circle_and_second_leg():
    # Path goes 1 m ahead then turns left; a 1.25 m circle exits on the second leg at y = 0.75.
    pts = np.array([[1.0, 0.0], [1.0, 2.0]])
    p = lookahead_point(pts, 1.25)
    np.testing.assert_allclose(p, [1.0, 0.75], atol=1e-12)
    assert np.hypot(*p) == pytest.approx(1.25)


def test_lookahead_point_beyond_path_end_is_last_vertex():
    pts = np.array([[0.3, 0.1], [0.4, 0.2]])
    np.testing.assert_allclose(lookahead_point(pts, 5.0), [0.4, 0.2])


def _obs(pose, path, std=(0.0, 0.0, 0.0), converged=True, last=(0.0, 0.0), otype="estimated"):
    from lrp_gym.config import ObservationConfig

    room = np.array([5.0, 5.0, 4.0])
    ot = make_observation(ObservationConfig(type=otype), room)
    s = path.project(np.asarray(pose[:2]))
    snap = NavSnapshot(
        np.asarray(pose, float),
        np.asarray(std, float),
        converged,
        1.0 if converged else 0.0,
        1,
        np.asarray(pose, float),
        path,
        s,
        s,
        np.asarray(last, float),
        room,
    )
    return ot.observe(snap)


def test_closed_loop_on_paper_path_reaches_goal_and_tracks_path(paper_cfg):
    """Perfect pose, exact kinematics: the controller follows the paper's 15 waypoints."""
    path = WaypointPath.from_points(np.array(paper_cfg.task.path))
    pol = PurePursuitPolicy()
    c = pol.config
    pose, last, xy = np.array(paper_cfg.robot.start_pose, float), np.zeros(2), []
    for _ in range(60):
        a, _ = pol.predict(_obs(pose, path, last=last))
        assert np.all(np.abs(a) <= 1.0)
        pose = integrate_unicycle(
            pose, a[0] * c.max_speed_mps, a[1] * c.max_turn_rate_rps, c.frame_period_s
        )
        last = a
        xy.append(pose[:2])
        if np.linalg.norm(pose[:2] - path.goal_m) <= paper_cfg.task.goal_tolerance_m:
            break
    assert np.linalg.norm(pose[:2] - path.goal_m) <= paper_cfg.task.goal_tolerance_m
    # 7 m at <= 2 m/s takes >= 14 frames; slowing in bends must not double that.
    assert 14 <= len(xy) <= 28
    from lrp_gym.experiments.episodes import cross_track_m

    assert cross_track_m(np.array(xy), path.waypoints_m).max() < 0.3


def test_speed_drops_with_uncertainty_and_near_goal():
    path = WaypointPath.from_points(np.array([[0.0, 0.0], [4.0, 0.0]]))
    pol = PurePursuitPolicy()
    c = pol.config
    sure = pol.predict(_obs([0.5, 0.0, 0.0], path))[0][0]
    vague = pol.predict(_obs([0.5, 0.0, 0.0], path, std=(0.2, 0.2, 0.1)))[0][0]
    lost = pol.predict(_obs([0.5, 0.0, 0.0], path, std=(1.0, 1.0, 0.1), converged=False))[0][0]
    near = pol.predict(_obs([3.8, 0.0, 0.0], path))[0][0]
    assert sure == pytest.approx(1.0)
    assert lost * c.max_speed_mps == pytest.approx(c.creep_speed_mps)
    assert lost < vague < sure
    # 0.2 m from the goal: at most approach_gain of the distance per frame.
    expected = max(c.approach_gain * 0.2 / c.frame_period_s, c.min_approach_speed_mps)
    assert near * c.max_speed_mps == pytest.approx(expected)


def test_unknown_heading_creeps_straight_and_behind_target_turns_on_spot():
    path = WaypointPath.from_points(np.array([[2.0, 2.0], [0.0, 2.0]]))
    pol = PurePursuitPolicy(PurePursuitConfig())
    a, _ = pol.predict(_obs([2.0, 2.0, 0.0], path, std=(0.05, 0.05, 2.0)))
    assert a[1] == 0.0 and a[0] > 0.0
    a, _ = pol.predict(_obs([2.0, 2.0, 0.0], path))  # target straight behind
    assert a[0] == 0.0 and abs(a[1]) == pytest.approx(1.0)


def test_predict_batch_matches_single_and_rejects_wrong_shape():
    path = WaypointPath.from_points(np.array([[0.0, 0.0], [1.0, 1.0], [3.0, 1.0]]))
    pol = PurePursuitPolicy()
    obs = np.stack([_obs([0.2, 0.1, 0.3], path), _obs([1.5, 1.2, -0.2], path)])
    batch, state = pol.predict(obs)
    assert batch.shape == (2, 2) and batch.dtype == np.float32 and state is None
    np.testing.assert_allclose(batch[1], pol.predict(obs[1])[0])
    with pytest.raises(ValueError, match="observation"):
        pol.predict(np.zeros(7))


def test_a_blind_creep_stops_short_of_the_wall_ahead_of_the_estimate():
    """Heading unknown (std 2 rad): the robot creeps straight where the floor ahead of the
    estimated pose is free for a few steps, and turns on the spot where it is not."""
    from agents.pure_pursuit import CREEP_LOOKAHEAD_STEPS
    from lrp_gym.world.room import Box, Room

    room = Room(
        size_m=np.array([5.0, 5.0, 4.0]),
        obstacles=(Box(np.array([2.0, 2.0, 0.0]), np.array([3.0, 3.0, 1.0])),),
    )
    radius = 0.2
    path = WaypointPath.from_points(np.array([[1.0, 1.0], [4.0, 1.0]]))
    wary = PurePursuitPolicy(PurePursuitConfig(), room, radius)
    c = wary.config
    reach = CREEP_LOOKAHEAD_STEPS * c.creep_speed_mps * c.frame_period_s  # 0.3 m
    unsure = (0.5, 0.5, 2.0)
    creep, turn = (c.creep_speed_mps, 0.0), (0.0, 0.5 * c.max_turn_rate_rps)

    def act(pose, pol=wary):
        return pol.control(_obs(np.array(pose, float), path, std=unsure, converged=False))

    edge = radius + c.creep_margin_m  # nearest the disc's centre may come to a wall
    assert act([1.0, 1.0, 0.0]) == pytest.approx(creep)  # in the open
    assert act([edge + reach + 0.01, 1.0, np.pi]) == pytest.approx(creep)  # just enough room
    assert act([edge + reach - 0.01, 1.0, np.pi]) == pytest.approx(turn)  # not quite: turn
    assert act([edge + 0.01, 1.0, 0.0]) == pytest.approx(creep)  # back to the wall: go
    # The same at the obstacle's face (x = 2), towards it and away from it.
    assert act([2.0 - edge - reach + 0.01, 2.5, 0.0]) == pytest.approx(turn)
    assert act([2.0 - edge - 0.01, 2.5, np.pi]) == pytest.approx(creep)
    # Without the room, or with the option off, the creep is blind; the default avoids walls.
    assert act([edge + 0.01, 1.0, np.pi], PurePursuitPolicy()) == pytest.approx(creep)
    off = PurePursuitConfig(avoid_walls_when_unsure=False)
    blind_creep = PurePursuitPolicy(off, room=room, robot_radius_m=radius)
    assert act([edge + reach - 0.01, 1.0, np.pi], blind_creep) == pytest.approx(creep)
    default = PurePursuitPolicy(room=room, robot_radius_m=radius)
    assert act([edge + reach - 0.01, 1.0, np.pi], default) == pytest.approx(turn)


def test_predict_scales_a_reverse_speed_by_the_reverse_limit():
    pol = PurePursuitPolicy(PurePursuitConfig(max_speed_mps=2.0, max_reverse_mps=0.2))
    pol.control = lambda obs: (-0.1, 0.0)  # a controller that backs off at 0.1 m/s
    action, _ = pol.predict(np.zeros(16))
    assert action[0] == pytest.approx(-0.5)  # the env multiplies by max_reverse_mps


def test_at_the_estimated_goal_in_an_episode_that_goes_on_the_robot_creeps_on():
    """The env ends an episode when the true pose reaches the goal, so an agent asked to act
    while its estimate sits on the goal knows the estimate is wrong. Turning on the spot there
    adds no evidence (frames are weighed by the distance driven): it creeps on instead."""
    from lrp_gym.world.room import Room

    path = WaypointPath.from_points(np.array([[1.0, 1.0], [3.0, 1.0]]))
    room = Room(size_m=np.array([5.0, 5.0, 4.0]), obstacles=())
    on = PurePursuitPolicy(PurePursuitConfig(arrived_m=0.125), room, 0.2)
    off = PurePursuitPolicy(PurePursuitConfig(arrived_m=0.0), room, 0.2)
    c = on.config
    # Estimate 5 cm short of the goal, facing away from it: the old rule turns to face it.
    at_goal = _obs([2.95, 1.0, np.pi], path)
    assert on.control(at_goal) == pytest.approx((c.creep_speed_mps, 0.0))
    speed, turn = off.control(at_goal)
    assert speed == 0.0 and abs(turn) > 0.0
    # 0.2 m short (outside arrived_m): the approach is unchanged.
    approach = _obs([2.8, 1.0, 0.0], path)
    assert on.control(approach) == pytest.approx(off.control(approach))
    # A goal 0.4 m from the wall, facing it: the creep turns on the spot (the room's clearance).
    by_wall = WaypointPath.from_points(np.array([[1.0, 4.6], [3.0, 4.6]]))
    speed, turn = on.control(_obs([2.95, 4.6, 0.5 * np.pi], by_wall))
    assert speed == 0.0 and turn == pytest.approx(0.5 * c.max_turn_rate_rps)


def test_from_env_puts_the_arrival_rule_inside_the_goal_tolerance():
    import gymnasium as gym

    from agents.pure_pursuit import ARRIVED_SHARE

    env = gym.make("LRPRadarNavFast-v0")
    tol = env.unwrapped.cfg.task.goal_tolerance_m
    assert PurePursuitPolicy.from_env(env).config.arrived_m == pytest.approx(ARRIVED_SHARE * tol)
    assert 0.0 < ARRIVED_SHARE < 1.0
    assert PurePursuitPolicy.from_env(env, arrived_m=0.0).config.arrived_m == 0.0
    env.close()


def test_a_patrol_passing_its_goal_mid_lap_is_not_arrived():
    """A patrol's goal lies on every lap: with waypoints still ahead, the robot follows them."""
    lap = np.array([[1.0, 1.0], [3.0, 1.0], [3.0, 3.0], [1.0, 3.0], [1.0, 1.0]])
    path = WaypointPath.from_points(np.vstack([lap, lap[1:]]))  # two laps, goal = start
    on = PurePursuitPolicy(PurePursuitConfig(arrived_m=0.125))
    off = PurePursuitPolicy(PurePursuitConfig(arrived_m=0.0))
    passing = _obs([1.0, 1.05, -0.5 * np.pi], path)  # 5 cm before the goal point, lap one
    assert on.control(passing) == pytest.approx(off.control(passing))
