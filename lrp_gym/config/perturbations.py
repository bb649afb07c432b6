"""Schema of the robustness perturbations (see :mod:`lrp_gym.perturbations`)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import (
    Field,
    model_validator,
)
from pydantic_core import PydanticCustomError

from lrp_gym.config.base import Fraction, NonNegFloat, PosVec3, Strict

# Robustness perturbations (see lrp_gym.perturbations). Each has a ``severity`` in [0, 1]; the
# physical parameters left at None are derived from it (documented per class there).
Severity = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]
FrameCount = Annotated[int, Field(ge=0, le=100_000)]


class PerturbationConfig(Strict):
    severity: Severity = 0.5


class ShadowingConfig(PerturbationConfig):
    """Reflectors hidden for ``frames`` frames by a static obstacle or a walking person."""

    mode: Literal["static", "person"] = "static"
    frames: Annotated[int, Field(ge=1, le=100_000)] | None = None
    reflectors: Annotated[int, Field(ge=1, le=1000)] = 1
    start_frames: Annotated[list[FrameCount], Field(min_length=2, max_length=2)] = [3, 20]
    person_size_m: PosVec3 = [0.5, 0.5, 1.8]


class MissedDetectionsConfig(PerturbationConfig):
    probability: Fraction | None = None


class ClutterConfig(PerturbationConfig):
    count: Annotated[int, Field(ge=0, le=10_000)] | None = None
    rcs_spread_db: NonNegFloat = 3.0


class DisplacedReflectorConfig(PerturbationConfig):
    shift_m: NonNegFloat | None = None
    reflectors: Annotated[int, Field(ge=1, le=1000)] = 1


class OdometrySlipConfig(PerturbationConfig):
    slip: Annotated[float, Field(gt=-1, le=10, allow_inf_nan=False)] | None = None
    heading_bias_dps: Annotated[float, Field(ge=-3600, le=3600, allow_inf_nan=False)] | None = None


class KidnappingConfig(PerturbationConfig):
    frames: Annotated[list[FrameCount], Field(min_length=2, max_length=2)] = [5, 15]
    min_jump_m: NonNegFloat | None = None


class InterferenceConfig(PerturbationConfig):
    burst_probability: Fraction | None = None
    burst_frames: Annotated[int, Field(ge=1, le=100_000)] = 3
    detections_per_frame: Annotated[int, Field(ge=0, le=10_000)] | None = None
    rcs_spread_db: NonNegFloat = 6.0


class IncidenceAngleConfig(PerturbationConfig):
    half_angle_deg: Annotated[float, Field(gt=0, le=180, allow_inf_nan=False)] | None = None
    cutoff_deg: Annotated[float, Field(gt=0, le=180, allow_inf_nan=False)] | None = None


class PerturbationsConfig(Strict):
    """Which perturbations are on (a section present = on); an unknown name is an error."""

    shadowing: ShadowingConfig | None = None
    missed_detections: MissedDetectionsConfig | None = None
    clutter: ClutterConfig | None = None
    displaced_reflector: DisplacedReflectorConfig | None = None
    odometry_slip: OdometrySlipConfig | None = None
    kidnapping: KidnappingConfig | None = None
    interference: InterferenceConfig | None = None
    incidence_angle: IncidenceAngleConfig | None = None

    @model_validator(mode="before")
    @classmethod
    def _known_names(cls, data: Any) -> Any:
        if isinstance(data, dict):
            unknown = [k for k in data if k not in cls.model_fields]
            if unknown:
                raise PydanticCustomError(
                    "perturbation",
                    "unknown perturbation {names}; known: {known}",
                    {"names": ", ".join(map(repr, unknown)), "known": ", ".join(cls.model_fields)},
                )
        return data

    def active(self) -> dict[str, PerturbationConfig]:
        """The perturbations that are on, by name."""
        return {k: v for k in type(self).model_fields if (v := getattr(self, k)) is not None}
