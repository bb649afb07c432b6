"""Defaults live only in the schema: the runtime objects built from a config carry none."""

from __future__ import annotations

import dataclasses
import inspect

import numpy as np
import pytest

from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.radar.cfar import Cfar2D
from lrp_gym.radar.channel import Channel
from lrp_gym.world.robot import DiffDriveLimits
from lrp_gym.world.room import Room, Surfaces
from lrp_gym.world.world import World


@pytest.mark.parametrize("cls", [Surfaces, DiffDriveLimits, Cfar2D])
def test_runtime_dataclasses_have_no_defaults(cls):
    with_default = [
        f.name
        for f in dataclasses.fields(cls)
        if f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING
    ]
    assert with_default == [], f"{cls.__name__} repeats schema defaults: {with_default}"


def test_likelihood_takes_measurement_and_clutter_settings_from_the_caller():
    params = inspect.signature(FingerprintModel.__init__).parameters
    for name in ("measurement_std_m", "clutter_probability", "max_range_m"):
        assert params[name].default is inspect.Parameter.empty, name


def test_a_scenario_builds_its_own_values(paper_cfg):
    cfg = paper_cfg
    world = World.from_config(cfg)
    s = cfg.room.surfaces
    assert world.room.surfaces == Surfaces(s.walls, s.floor, s.ceiling, s.obstacles)
    assert world.robot.max_speed_mps == cfg.robot.max_speed_mps
    cfar = Cfar2D.from_config(cfg.radar.cfar)
    assert (cfar.method, cfar.os_rank, cfar.pfa) == (
        cfg.radar.cfar.method,
        cfg.radar.cfar.os_rank,
        cfg.radar.cfar.pfa,
    )


def test_channel_refuses_a_geometry_only_room(paper_cfg):
    world = World.from_config(paper_cfg)
    with pytest.raises(ValueError, match="room.surfaces"):
        Channel(Room(np.array([5.0, 5.0, 3.0])), world.layout, world.fmcw.wavelength_m, 1.0)
