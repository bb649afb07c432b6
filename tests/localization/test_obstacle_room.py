"""AMCL, the look-up table, the env and the evaluator in a room with obstacles.

Before issue #13, AMCL passed (N, 3) particles to ``Room.free`` and every scenario with an
obstacle crashed at its first update.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from lrp_gym.cli import main
from lrp_gym.config import load_scenario
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.lut import LookupTable
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world import Box, Room, World

BOX = {"min": [0.8, 1.4, 0.0], "max": [2.2, 2.6, 1.0]}


@pytest.fixture(scope="module")
def cfg():
    return load_scenario("ipin2023").with_overrides(
        {
            "room": {"obstacles": [BOX]},
            "localization": {"initial_particles": 2000, "max_particles": 2000},
        }
    )


@pytest.fixture(scope="module")
def world(cfg):
    return World.from_config(cfg)


def _in_box(xy: np.ndarray, margin_m: float) -> np.ndarray:
    lo, hi = np.array(BOX["min"][:2]) - margin_m, np.array(BOX["max"][:2]) + margin_m
    return np.all((xy >= lo) & (xy <= hi), axis=-1)


def _box_distance_m(xy: np.ndarray) -> np.ndarray:
    """Distance of floor points (N, 2) from the box's footprint (0 inside)."""
    lo, hi = np.array(BOX["min"][:2]), np.array(BOX["max"][:2])
    return np.hypot(*(xy - np.clip(xy, lo, hi)).T)


def test_room_free_takes_floor_points_only(world):
    with pytest.raises(ValueError, match=r"\(\.\.\., 2\)"):
        world.room.free(np.zeros((4, 3)))
    assert world.room.free(np.array([[1.5, 2.0], [0.5, 0.5]])).tolist() == [False, True]


def test_path_free_measures_legs_not_only_waypoints():
    assert Room(np.array([5.0, 5.0, 3.0])).path_free([[0.5, 0.5], [4.5, 4.5]], 0.3).all()
    room = Room(np.array([5.0, 5.0, 3.0]), (Box([2, 2, 0], [3, 3, 1]),))
    # Both ends free, the diagonal crosses the box; a leg 0.25 m beside it is free at 0.2 m
    # and blocked at 0.3 m (the disc would touch the box).
    assert not room.path_free([[0.5, 0.5], [4.5, 4.5]], 0.0)[0]
    assert room.path_free([[1.75, 0.5], [1.75, 4.5]], 0.2)[0]
    assert not room.path_free([[1.75, 0.5], [1.75, 4.5]], 0.3)[0]


def test_amcl_keeps_particles_out_of_the_obstacle_and_converges(cfg, world):
    rng = np.random.default_rng(0)
    amcl = Amcl(world, cfg.localization)
    amcl.reset(rng)
    r = world.robot.radius_m
    assert world.room.free(amcl.particles[:, :2], r).all()
    assert not _in_box(amcl.particles[:, :2], 0.0).any()
    pose = np.array([1.0, 1.0, 0.0])
    for _ in range(8):
        fp = Fingerprint.from_true(world.layout, world.radar_position(pose[:2]), 0.02)
        est = amcl.update(np.zeros(3), fp, rng)
    # Particles pushed into the obstacle by the motion noise weigh nothing.
    inside = ~world.room.free(amcl.particles[:, :2], r)
    assert np.all(amcl.weights[inside] == 0.0) if inside.any() else True
    assert np.hypot(*(est.pose[:2] - pose[:2])) < 0.3


def test_lut_tabulates_only_free_cells_and_answers(world):
    lut = LookupTable(world, 0.1, 0.1)
    assert not _in_box(lut.positions_m, -1e-9).any()
    fp = Fingerprint.from_true(world.layout, world.radar_position(np.array([1.0, 1.0])))
    assert np.hypot(*(lut.query(fp).pose[:2] - [1.0, 1.0])) < 0.5


def test_env_steps_in_a_room_with_an_obstacle(cfg):
    import gymnasium as gym

    import lrp_gym  # noqa: F401

    env = gym.make("LRPRadarNavFast-v0", scenario=cfg.with_overrides({"task": {"mode": "goal"}}))
    env.action_space.seed(0)
    for seed in range(3):
        obs, info = env.reset(seed=seed)
        for _ in range(5):
            obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
            assert env.observation_space.contains(obs) and np.isfinite(reward)
            # The robot's disc never enters the obstacle (a collision stops it before). The
            # disc may pass a corner closer than its radius along each axis: the distance counts.
            assert _box_distance_m(info["true_pose"][None, :2])[0] >= cfg.robot.radius_m - 1e-9
            if terminated:
                break
    env.close()


def test_evaluate_cli_runs_in_a_room_with_an_obstacle(capsys):
    box = "{min: [0.8, 1.4, 0], max: [2.2, 2.6, 1.0]}"
    with pytest.raises(SystemExit) as exc:
        main(
            [
                "evaluate",
                "--episodes",
                "1",
                "--env",
                "LRPRadarNavFast-v0",
                "--json",
                "--set",
                f"room.obstacles=[{box}]",
                "--set",
                "localization.initial_particles=200",
                "--set",
                "localization.max_particles=200",
            ]
        )
    assert exc.value.code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["episodes"] == 1 and doc["per_episode"][0]["steps"] >= 1
    assert np.isfinite(doc["mean_loc_error_m"])
