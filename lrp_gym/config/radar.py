"""Schema of the radar: waveform (given or derived from requirements), noise, CFAR."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import (
    Field,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from lrp_gym.config.base import NonNegFloat, PositiveFloat, Probability, Strict, _fmt
from lrp_gym.waveform import FmcwParameters


class CfarConfig(Strict):
    """2-D CFAR on the range-Doppler power map; the threshold follows from ``pfa``."""

    method: Literal["CA", "SO", "GO", "OS"] = "OS"
    guard_cells: Annotated[list[int], Field(min_length=2, max_length=2)] = [2, 1]
    training_cells: Annotated[list[int], Field(min_length=2, max_length=2)] = [8, 3]
    pfa: Probability = 1e-6
    os_rank: Annotated[float, Field(gt=0, le=1)] = 0.6

    @field_validator("guard_cells", "training_cells")
    @classmethod
    def _non_negative(cls, v: list[int]) -> list[int]:
        if any(c < 0 for c in v):
            raise PydanticCustomError(
                "cells", "expected 2 non-negative integers, got {v}", {"v": _fmt(v)}
            )
        return v


class RequirementsConfig(Strict):
    """Wanted radar performance; when given, the waveform is derived from it."""

    range_resolution_m: PositiveFloat
    max_range_m: PositiveFloat
    velocity_resolution_mps: PositiveFloat
    max_velocity_mps: PositiveFloat


class RadarConfig(Strict):
    carrier_hz: PositiveFloat = 60e9
    bandwidth_hz: PositiveFloat = 2e9
    chirp_period_s: PositiveFloat = 220e-6
    samples_per_chirp: Annotated[int, Field(ge=8, le=8192)] = 256
    chirps_per_frame: Annotated[int, Field(ge=2, le=4096)] = 32
    requirements: RequirementsConfig | None = None
    mount_height_m: NonNegFloat = 0.3
    tx_power_dbm: Annotated[float, Field(ge=-30, le=40)] = 10.0
    tx_gain_dbi: Annotated[float, Field(ge=-10, le=40)] = 8.0
    rx_gain_dbi: Annotated[float, Field(ge=-10, le=40)] = 8.0
    noise_figure_db: Annotated[float, Field(ge=0, le=40)] = 12.0
    temperature_k: PositiveFloat = 290.0
    noise: bool = True
    max_reflection_order: Annotated[int, Field(ge=0, le=4)] = 2
    window: Literal["hann", "hamming", "blackman", "rect"] = "hann"
    cfar: CfarConfig = CfarConfig()
    min_range_m: NonNegFloat = 0.3
    fidelity: Literal["signal", "detections"] = "signal"
    #: the robot blocks paths that reach the radar (on its top deck) from below its horizontal
    #: plane and paths that retrace themselves through the radar (lrp_gym/radar/channel.py)
    body_shadowing: bool = True
    #: zenith angle (deg) where the upward-facing antenna cone is 3 dB down; None = omni
    antenna_half_power_deg: Annotated[float, Field(gt=0, le=180)] | None = 75.0
    #: side/back lobe level of that cone relative to boresight (dB)
    antenna_floor_db: Annotated[float, Field(ge=-60, le=0)] = -20.0

    def fmcw(self) -> FmcwParameters:
        """The waveform: from ``requirements`` when given, else from the explicit fields."""
        if self.requirements is not None:
            return FmcwParameters.from_requirements(
                carrier_hz=self.carrier_hz, **self.requirements.model_dump()
            )
        return FmcwParameters(
            carrier_hz=self.carrier_hz,
            bandwidth_hz=self.bandwidth_hz,
            chirp_period_s=self.chirp_period_s,
            samples_per_chirp=self.samples_per_chirp,
            chirps_per_frame=self.chirps_per_frame,
        )

    @model_validator(mode="after")
    def _cfar_fits(self) -> RadarConfig:
        fm = self.fmcw()
        g, t = self.cfar.guard_cells, self.cfar.training_cells
        if (
            2 * (g[0] + t[0]) + 1 > fm.samples_per_chirp
            or 2 * (g[1] + t[1]) + 1 > fm.chirps_per_frame
        ):
            raise PydanticCustomError(
                "cfar",
                "cfar window {w} cells does not fit the {n} range x {m} Doppler map",
                {
                    "w": _fmt([2 * (g[0] + t[0]) + 1, 2 * (g[1] + t[1]) + 1]),
                    "n": fm.samples_per_chirp,
                    "m": fm.chirps_per_frame,
                },
            )
        if sum(t) == 0:
            raise PydanticCustomError("cfar", "cfar needs at least one training cell", {})
        return self
