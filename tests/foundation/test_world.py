"""World model: kinematics against closed forms, odometry, room geometry, RCS models."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.world import (
    Box,
    OdometryNoise,
    Room,
    apply_odometry,
    integrate_unicycle,
    odometry_delta,
    rcs_peak_m2,
    wrap_angle,
)


def test_straight_line_motion():
    pose = integrate_unicycle(np.array([1.0, 2.0, np.pi / 4]), 1.0, 0.0, 2.0)
    assert np.allclose(pose, [1 + np.sqrt(2), 2 + np.sqrt(2), np.pi / 4])


def test_arc_motion_matches_circle():
    # v = 1 m/s, omega = pi/2 rad/s for 1 s from the origin heading +x: a quarter circle of r=2/pi.
    r = 2.0 / np.pi
    pose = integrate_unicycle(np.zeros(3), 1.0, np.pi / 2, 1.0)
    assert np.allclose(pose, [r, r, np.pi / 2])


def test_turn_in_place():
    pose = integrate_unicycle(np.array([1.0, 1.0, 3.0]), 0.0, 1.0, 0.5)
    assert np.allclose(pose[:2], [1, 1])
    assert pose[2] == pytest.approx(wrap_angle(3.5))


def test_integration_is_vectorised_and_consistent():
    rng = np.random.default_rng(0)
    poses = rng.uniform(-1, 1, (50, 3))
    v, w = rng.uniform(0, 2, 50), rng.uniform(-2, 2, 50)
    batch = integrate_unicycle(poses, v, w, 0.25)
    single = np.array([integrate_unicycle(p, a, b, 0.25) for p, a, b in zip(poses, v, w)])
    assert np.allclose(batch, single)
    # Ten small steps equal one long step (exact integration).
    p = poses[0]
    for _ in range(10):
        p = integrate_unicycle(p, v[0], w[0], 0.025)
    assert np.allclose(p, batch[0])


def test_odometry_delta_inverts_apply():
    rng = np.random.default_rng(1)
    a = rng.uniform([0, 0, -np.pi], [5, 5, np.pi], (100, 3))
    b = rng.uniform([0, 0, -np.pi], [5, 5, np.pi], (100, 3))
    d = odometry_delta(a, b)
    assert np.allclose(apply_odometry(a, d)[:, :2], b[:, :2])
    assert np.allclose(wrap_angle(apply_odometry(a, d)[:, 2] - b[:, 2]), 0, atol=1e-12)


def test_odometry_noise_has_the_configured_spread():
    noise = OdometryNoise(sigma_turn_rad=np.deg2rad(5), sigma_distance_m=0.05)
    draws = noise.sample(np.array([0.1, 0.5, -0.1]), 200_000, np.random.default_rng(2))
    assert draws.shape == (200_000, 3)
    assert np.std(draws[:, 1]) == pytest.approx(0.05, rel=0.02)
    assert np.std(draws[:, 0]) == pytest.approx(np.deg2rad(5), rel=0.02)
    assert np.mean(draws[:, 1]) == pytest.approx(0.5, abs=1e-3)
    alphas = OdometryNoise(0.0, 0.0, (0.1, 0.0, 0.2, 0.0))
    assert np.allclose(alphas.std(np.array([0.5, 2.0, 0.0])), [0.05, 0.4, 0.0])


def test_room_free_space_and_obstacles():
    room = Room(np.array([5.0, 4.0, 3.0]), (Box([2, 2, 0], [3, 3, 1]),))
    xy = np.array([[0.1, 0.1], [2.5, 2.5], [1.9, 2.5], [1.7, 2.5], [4.95, 1.0], [-0.1, 1]])
    assert room.free(xy).tolist() == [True, False, True, True, True, False]
    assert room.free(xy, clearance_m=0.2).tolist() == [False, False, False, True, False, False]


def test_segments_blocked_by_box():
    room = Room(np.array([5.0, 5.0, 4.0]), (Box([2, 2, 0], [3, 3, 2]),))
    start = np.array([[1, 2.5, 1], [1, 2.5, 3], [2.5, 1, 0.5], [1, 1, 1], [2.5, 2.5, 3]])
    end = np.array([[4, 2.5, 1], [4, 2.5, 3], [2.5, 1.9, 0.5], [1, 4, 1], [2.5, 2.5, 1.5]])
    assert room.segments_blocked(start, end).tolist() == [True, False, False, False, True]


def test_rcs_models():
    lam = 5e-3
    # A 5 cm trihedral at 5 mm is about 0 dBsm (the paper's design point).
    assert 10 * np.log10(rcs_peak_m2("trihedral", lam, edge_m=0.05)) == pytest.approx(0.2, abs=0.1)
    # A 0 dBsm sphere needs a diameter of about 1.13 m.
    assert rcs_peak_m2("sphere", lam, diameter_m=1.128) == pytest.approx(1.0, rel=0.01)
    assert rcs_peak_m2("point", lam, rcs_dbsm=-10) == pytest.approx(0.1)
    assert rcs_peak_m2("luneburg", lam, diameter_m=0.1) > rcs_peak_m2("sphere", lam, diameter_m=0.1)
    with pytest.raises(ValueError, match="unknown reflector kind"):
        rcs_peak_m2("mirror", lam)


def test_trihedral_pattern_and_layout_distances(paper_world):
    layout = paper_world.layout
    t = layout.types[0]
    assert t.pattern(np.array([1.0]))[0] == pytest.approx(1.0)
    assert t.pattern(np.array([np.cos(np.deg2rad(40))]))[0] == pytest.approx(0.5, rel=0.01)
    assert t.pattern(np.array([-0.1]))[0] == 0.0
    radar = paper_world.radar_position(np.array([2.0, 2.0]))
    expected = np.linalg.norm(layout.positions_m - radar, axis=1)
    assert np.allclose(paper_world.true_distances_m(np.array([2.0, 2.0])), expected)
    rcs = layout.effective_rcs_m2(radar)
    assert np.all(rcs <= layout.rcs_m2 + 1e-12) and np.all(rcs > 0)
