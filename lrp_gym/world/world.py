"""The runtime world built from a validated scenario."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from lrp_gym.waveform import FmcwParameters
from lrp_gym.world.reflectors import ReflectorLayout, ReflectorType, rcs_peak_m2
from lrp_gym.world.robot import DiffDriveLimits, OdometryNoise
from lrp_gym.world.room import Box, Room, Surfaces

if TYPE_CHECKING:
    # The schema validates against the world's geometry (config/checks.py), so it sits above it.
    from lrp_gym.config import ScenarioConfig


@dataclass(frozen=True)
class World:
    """Everything static about a scenario, as arrays and plain dataclasses.

    Attributes
    ----------
    room : Room
    layout : ReflectorLayout
    fmcw : FmcwParameters
    mount_height_m : float
        Height of the radar's phase centre above the floor.
    robot : DiffDriveLimits
    odometry_noise : OdometryNoise
        The robot's true odometry error (not AMCL's motion model).
    """

    room: Room
    layout: ReflectorLayout
    fmcw: FmcwParameters
    mount_height_m: float
    robot: DiffDriveLimits
    odometry_noise: OdometryNoise

    @classmethod
    def from_config(cls, cfg: ScenarioConfig) -> World:
        room = Room(
            size_m=np.array(cfg.room.size),
            obstacles=tuple(Box(np.array(b.min), np.array(b.max)) for b in cfg.room.obstacles),
            surfaces=Surfaces(**cfg.room.surfaces.model_dump()),
        )
        fmcw = cfg.fmcw()
        names = list(cfg.reflectors.types)
        types = []
        for name in names:
            t = cfg.reflectors.types[name]
            half, cutoff = t.pattern_angles()
            rcs = rcs_peak_m2(
                t.kind,
                fmcw.wavelength_m,
                edge_m=t.edge_m,
                diameter_m=t.diameter_m,
                elements=t.elements,
                element_area_m2=t.element_area_m2,
                rcs_dbsm=t.rcs_dbsm,
            )
            types.append(ReflectorType(name, t.kind, rcs, half, cutoff))
        mount = cfg.radar.mount_height_m
        centre = np.array([room.size_m[0] / 2, room.size_m[1] / 2, mount])
        positions = np.array([r.position for r in cfg.reflectors.layout], dtype=float).reshape(
            -1, 3
        )
        axes = np.array(
            [
                r.axis if r.axis is not None else centre - np.array(r.position)
                for r in cfg.reflectors.layout
            ],
            dtype=float,
        ).reshape(-1, 3)
        layout = ReflectorLayout(
            positions_m=positions,
            type_index=np.array([names.index(r.type) for r in cfg.reflectors.layout], dtype=int),
            axes=axes,
            types=tuple(types),
        )
        rc = cfg.robot
        robot = DiffDriveLimits(
            max_speed_mps=rc.max_speed_mps,
            max_reverse_mps=rc.max_reverse_mps,
            max_turn_rate_rps=np.deg2rad(rc.max_turn_rate_dps),
            radius_m=rc.radius_m,
        )
        on = rc.odometry_noise
        odo = OdometryNoise(np.deg2rad(on.sigma_turn_deg), on.sigma_distance_m, tuple(on.alphas))
        return cls(room, layout, fmcw, mount, robot, odo)

    def radar_position(self, xy: np.ndarray) -> np.ndarray:
        """3-D radar positions (..., 3) for robot floor positions (..., 2)."""
        xy = np.asarray(xy, dtype=float)
        z = np.full(xy.shape[:-1] + (1,), self.mount_height_m)
        return np.concatenate([xy, z], axis=-1)

    def true_distances_m(self, xy: np.ndarray) -> np.ndarray:
        """Radar-to-reflector slant distances (..., M) for robot positions (..., 2)."""
        return self.layout.distances_m(self.radar_position(xy))
