"""The histogram (grid) filter against a brute-force posterior, its motion update and the
paper path."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.config import MotionNoiseConfig, load_scenario
from lrp_gym.localization import Amcl, GridFilter, make_localizer
from lrp_gym.localization.particle_motion import sample_motion
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world import World
from lrp_gym.world.robot import odometry_delta
from lrp_gym.world.trajectory import path_trajectory

TINY_LAYOUT = [
    {"position": [0.2, 0.3, 2.5], "type": "A"},
    {"position": [1.3, 0.5, 2.5], "type": "A"},
    {"position": [0.6, 1.35, 2.5], "type": "A"},
]
# True poses of the tiny-room frames (x_m, y_m, theta_rad).
TINY_POSES = np.array([[0.45, 0.5, 0.3], [0.75, 0.6, 0.9], [0.9, 0.85, 1.6]])


@pytest.fixture(scope="module")
def tiny():
    cfg = load_scenario("ipin2023").with_overrides(
        {
            "room": {"size": [1.5, 1.5, 3.0]},
            "reflectors": {"layout": TINY_LAYOUT},
            "robot": {"start_pose": [0.45, 0.5, 0.3]},
            "task": {"path": [[0.45, 0.5], [1.0, 0.5]]},
            "localization": {"grid_cell_m": 0.1, "grid_cell_deg": 10.0, "likelihood_exponent": 1.0},
        }
    )
    return World.from_config(cfg), cfg.localization


def _fingerprint(world, pose):
    return Fingerprint.from_true(world.layout, world.radar_position(pose[:2]), 0.05)


def _odometries(poses):
    return [np.zeros(3)] + [odometry_delta(a, b) for a, b in zip(poses[:-1], poses[1:])]


def test_first_frame_is_the_normalised_likelihood(tiny):
    world, loc = tiny
    still = loc.model_copy(
        update={"motion_noise": MotionNoiseConfig(sigma_turn_deg=0.0, sigma_distance_m=0.0)}
    )
    grid = GridFilter(world, still)
    grid.reset()
    fp = _fingerprint(world, TINY_POSES[0])
    grid.update(np.zeros(3), fp)
    xy = np.stack(np.meshgrid(grid.x_m, grid.y_m, indexing="ij"), axis=-1)[grid.free]
    lik = np.exp(grid.model.log_likelihood(xy, fp))
    expected = np.zeros(grid.free.shape)
    expected[grid.free] = lik / lik.sum()
    np.testing.assert_allclose(grid.xy_marginal(), expected, rtol=1e-12, atol=1e-15)
    # Headings stay uniform: the likelihood does not depend on them.
    np.testing.assert_allclose(grid.density.sum(axis=(1, 2)), 1.0 / grid.shape[0], rtol=1e-12)


def _brute_force(world, loc, grid, n, rng):
    """Importance-sampled posterior marginals over the grid's xy and heading cells after
    TINY_POSES' frames, and the effective sample size."""
    amcl = Amcl(world, loc)
    poses = amcl.uniform_particles(n, rng)
    logw = np.zeros(n)
    for pose, odo in zip(TINY_POSES, _odometries(TINY_POSES)):
        poses = sample_motion(poses, odo, amcl.motion_noise, rng)
        logw[~world.room.free(poses[:, :2], amcl.clearance_m)] = -np.inf
        logw += amcl.model.log_likelihood(poses, _fingerprint(world, pose))
    w = np.exp(logw - logw.max())
    w /= w.sum()
    n_h, nx, ny = grid.shape
    ix = np.clip((poses[:, 0] / grid.cell_m).astype(int), 0, nx - 1)  # outside: weight 0
    iy = np.clip((poses[:, 1] / grid.cell_m).astype(int), 0, ny - 1)
    xy = np.bincount(ix * ny + iy, w, minlength=nx * ny).reshape(nx, ny)
    k = np.round((poses[:, 2] + np.pi) / grid.cell_rad).astype(int) % n_h
    return xy, np.bincount(k, w, minlength=n_h), 1.0 / (w**2).sum()


@pytest.mark.parametrize("n", [400_000, pytest.param(2_000_000, marks=pytest.mark.slow)])
def test_posterior_matches_importance_sampling(tiny, n):
    world, loc = tiny
    grid = GridFilter(world, loc)
    grid.reset()
    for pose, odo in zip(TINY_POSES, _odometries(TINY_POSES)):
        grid.update(odo, _fingerprint(world, pose))
    ref_xy, ref_heading, ess = _brute_force(world, loc, grid, n, np.random.default_rng(1))
    assert ess > 20_000  # enough samples for a reference on ~120 cells
    # Total variation distances (measured: 0.014 in xy, 0.009 in heading at n = 400k).
    tv = 0.5 * np.abs(grid.xy_marginal() - ref_xy).sum()
    assert tv < 0.05, tv
    tv_heading = 0.5 * np.abs(grid.density.sum(axis=(1, 2)) - ref_heading).sum()
    assert tv_heading < 0.05, tv_heading
    # And not by accident: a grid that skipped the last frame is much further off.
    stale = GridFilter(world, loc)
    stale.reset()
    for pose, odo in zip(TINY_POSES[:-1], _odometries(TINY_POSES)[:-1]):
        stale.update(odo, _fingerprint(world, pose))
    assert 0.5 * np.abs(stale.xy_marginal() - ref_xy).sum() > 3.0 * tv


def _paper_loc():
    return load_scenario("ipin2023").localization.model_copy(
        update={"grid_cell_m": 0.05, "grid_cell_deg": 5.0}
    )


def _peaked(world, loc, pose):
    cfg = loc.model_copy(update={"init": "gaussian", "init_std": [0.02, 0.02, 0.02]})
    grid = GridFilter(world, cfg)
    grid.reset(pose=np.asarray(pose, dtype=float))
    return grid


def _mode(grid):
    k, i, j = np.unravel_index(np.argmax(grid.density), grid.shape)
    return grid.x_m[i], grid.y_m[j], grid.headings_rad[k]


@pytest.mark.parametrize("odometry", [(0.0, 0.5, 0.6), (np.pi / 2, 0.5, -0.3)])
def test_motion_moves_a_delta_by_the_odometry(paper_world, odometry):
    grid = _peaked(paper_world, _paper_loc(), (1.5, 2.0, 0.0))
    kept = grid.predict(np.asarray(odometry))
    assert kept == pytest.approx(1.0, abs=1e-9)  # far from the walls: no mass lost
    assert grid.density.sum() == pytest.approx(1.0)
    rot1, trans, rot2 = odometry
    x, y, th = _mode(grid)
    assert abs(x - (1.5 + trans * np.cos(rot1))) <= grid.cell_m + 1e-9
    assert abs(y - (2.0 + trans * np.sin(rot1))) <= grid.cell_m + 1e-9
    d_th = (th - (rot1 + rot2) + np.pi) % (2 * np.pi) - np.pi
    assert abs(d_th) <= grid.cell_rad + 1e-9


def test_motion_drops_the_mass_that_leaves_the_free_space_as_amcl_does(paper_world):
    loc = _paper_loc()
    start = np.array([0.5, 2.5, np.pi])  # facing the wall; free space starts at x = 0.2
    grid = _peaked(paper_world, loc, start)
    odo = np.array([0.0, 0.3, 0.0])
    kept = grid.predict(odo)
    rng = np.random.default_rng(0)
    amcl = Amcl(paper_world, loc)
    cloud = start + rng.standard_normal((200_000, 3)) * 0.02
    moved = sample_motion(cloud, odo, amcl.motion_noise, rng)
    share = np.mean(paper_world.room.free(moved[:, :2], amcl.clearance_m))
    assert 0.2 < share < 0.8  # the test is about a partial loss
    assert kept == pytest.approx(share, abs=0.06)
    assert grid.density.sum() == pytest.approx(1.0)
    assert not grid.density[:, ~grid.free].any()


def test_grid_draws_no_random_numbers(tiny):
    world, loc = tiny
    rng = np.random.default_rng(7)
    before = rng.bit_generator.state
    grid = make_localizer(world, loc.model_copy(update={"method": "grid"}))
    assert isinstance(grid, GridFilter)
    grid.reset(rng)
    for pose, odo in zip(TINY_POSES, _odometries(TINY_POSES)):
        grid.update(odo, _fingerprint(world, pose), rng)
    assert rng.bit_generator.state == before


def test_particles_expose_the_posterior(tiny):
    world, loc = tiny
    grid = GridFilter(world, loc)
    grid.reset()
    est = grid.update(np.zeros(3), _fingerprint(world, TINY_POSES[0]))
    p, w = grid.particles, grid.weights
    assert p.shape == (len(w), 3) and w.sum() == pytest.approx(1.0)
    assert est.n_particles >= len(w)
    mean = w @ p[:, :2]
    marg = grid.xy_marginal()
    exact = np.array([grid.x_m @ marg.sum(axis=1), marg.sum(axis=0) @ grid.y_m])
    np.testing.assert_allclose(mean, exact, atol=0.02)


def test_localises_on_the_paper_path_from_a_uniform_prior(paper_cfg, paper_world):
    loc = paper_cfg.localization.model_copy(update={"method": "grid", "init": "uniform"})
    traj = path_trajectory(np.asarray(paper_cfg.task.path), paper_cfg.robot.max_speed_mps, 0.25)
    grid = make_localizer(paper_world, loc)
    grid.reset()
    poses = traj.poses[:8]
    errors = []
    for pose, odo in zip(poses, _odometries(poses)):
        fp = Fingerprint.from_true(paper_world.layout, paper_world.radar_position(pose[:2]))
        est = grid.update(odo, fp)
        errors.append(np.hypot(*(est.pose[:2] - pose[:2])))
    assert max(errors[5:]) < 0.2, errors
    assert est.converged and est.position_std_m < 0.3
