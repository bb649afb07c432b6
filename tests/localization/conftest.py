"""Fixtures for the localisation tests: a fixed 4-reflector layout (independent of edits to the
shipped paper scenario) and its noiseless path."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.config import load_scenario
from lrp_gym.world import World
from lrp_gym.world.trajectory import path_trajectory

LAYOUT = [
    {"position": [0.9, 1.3, 3.0], "type": "A"},
    {"position": [3.8, 0.7, 3.0], "type": "A"},
    {"position": [4.3, 3.6, 3.0], "type": "A"},
    {"position": [1.6, 4.4, 3.0], "type": "A"},
]


@pytest.fixture(scope="session")
def loc_cfg():
    base = load_scenario("ipin2023")
    # These tests feed synthetic fingerprints with independent errors per frame: the untempered
    # likelihood is the right model for them (tempering is for the radar's correlated errors),
    # and they hold no returns of the room, so the model expects none.
    return base.with_overrides(
        {
            "reflectors": {"layout": LAYOUT},
            "localization": {"likelihood_exponent": 1.0, "structure_probability": 0.0},
        }
    )


@pytest.fixture(scope="session")
def loc_world(loc_cfg):
    return World.from_config(loc_cfg)


@pytest.fixture(scope="session")
def loc_poses(loc_cfg):
    traj = path_trajectory(
        np.asarray(loc_cfg.task.path), loc_cfg.robot.max_speed_mps, loc_cfg.task.frame_period_s
    )
    return traj.poses
