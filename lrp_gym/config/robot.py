"""Schema of the robot: drive limits and true odometry noise."""

from __future__ import annotations

from typing import Annotated

from pydantic import (
    Field,
)

from lrp_gym.config.base import NonNegFloat, Pose, PositiveFloat, Strict


class OdometryNoiseConfig(Strict):
    """Gaussian noise on turned angle and travelled distance (plus optional AMCL alphas)."""

    sigma_turn_deg: NonNegFloat = 0.2
    sigma_distance_m: NonNegFloat = 0.002
    alphas: Annotated[list[NonNegFloat], Field(min_length=4, max_length=4)] = [
        0.05,
        0.01,
        0.03,
        0.01,
    ]


class RobotConfig(Strict):
    start_pose: Pose = [0.75, 0.75, 0.0]
    radius_m: PositiveFloat = 0.2
    max_speed_mps: PositiveFloat = 2.0
    max_reverse_mps: NonNegFloat = 0.2
    max_turn_rate_dps: PositiveFloat = 180.0
    odometry_noise: OdometryNoiseConfig = OdometryNoiseConfig()
