"""World model: room and obstacles, reflectors and their RCS, robot kinematics and odometry."""

from lrp_gym.world.reflectors import ReflectorLayout, ReflectorType, rcs_peak_m2
from lrp_gym.world.robot import (
    DiffDriveLimits,
    OdometryNoise,
    apply_odometry,
    integrate_unicycle,
    noisy_odometry,
    odometry_delta,
    wrap_angle,
)
from lrp_gym.world.room import Box, Room, Surfaces
from lrp_gym.world.world import World

__all__ = [
    "Box",
    "DiffDriveLimits",
    "OdometryNoise",
    "ReflectorLayout",
    "ReflectorType",
    "Room",
    "Surfaces",
    "World",
    "apply_odometry",
    "integrate_unicycle",
    "noisy_odometry",
    "odometry_delta",
    "rcs_peak_m2",
    "wrap_angle",
]
