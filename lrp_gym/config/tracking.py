"""Schema of the LRP tracker."""

from __future__ import annotations

from typing import Annotated

from pydantic import (
    Field,
    model_validator,
)
from pydantic_core import PydanticCustomError

from lrp_gym.config.base import NonNegFloat, PositiveFloat, Probability, Strict


class TrackingConfig(Strict):
    """LRP identification and tracking (see :mod:`lrp_gym.tracking`).

    A detection may be a reflector of a type when its RCS estimate lies within
    ``[peak - rcs_tolerance_db - rcs_pattern_loss_db, peak + rcs_tolerance_db]`` (the
    incidence-angle pattern only ever lowers the apparent RCS). ``rate_gate_mps`` bounds the
    jump of the measured radial velocity a track accepts in one frame (a turn of the robot).
    """

    rcs_tolerance_db: PositiveFloat = 8.0
    rcs_pattern_loss_db: NonNegFloat = 6.0
    rate_gate_mps: PositiveFloat = 3.0
    measurement_std_m: PositiveFloat = 0.02
    velocity_std_mps: PositiveFloat = 0.1
    process_accel_std_mps2: PositiveFloat = 2.0
    ego_accel_std_mps2: PositiveFloat = Field(
        default=0.5,
        description="process noise of the static-point prediction (used with ego motion)",
    )
    nis_weight: NonNegFloat = Field(
        default=0.0,
        description="how strongly a track's running innovation counts against it as a reflector "
        "(off by default: on the paper path it made the identification worse, 0.34 -> 0.51 m)",
    )
    gate_probability: Probability = 0.997
    confirm_hits: Annotated[int, Field(ge=1)] = 2
    confirm_window: Annotated[int, Field(ge=1)] = 3
    max_coast_frames: Annotated[int, Field(ge=0)] = 5

    @model_validator(mode="after")
    def _m_of_n(self) -> TrackingConfig:
        if self.confirm_hits > self.confirm_window:
            raise PydanticCustomError(
                "m_of_n",
                "confirm_hits ({m}) cannot exceed confirm_window ({n})",
                {"m": self.confirm_hits, "n": self.confirm_window},
            )
        return self
