"""Schema of the room (size, obstacles, surfaces) and of the reflectors."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import (
    Field,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from lrp_gym.config.base import Fraction, PositiveFloat, PosVec3, Strict, Vec3, _fmt


class BoxConfig(Strict):
    """Axis-aligned obstacle box."""

    min: Vec3
    max: Vec3
    name: str = ""

    @model_validator(mode="after")
    def _ordered(self) -> BoxConfig:
        if any(lo >= hi for lo, hi in zip(self.min, self.max, strict=True)):
            raise PydanticCustomError(
                "box",
                "min {lo} must be below max {hi} on every axis",
                {"lo": _fmt(self.min), "hi": _fmt(self.max)},
            )
        return self


class SurfacesConfig(Strict):
    """Amplitude reflection coefficients |Gamma| of the surfaces (0 = absorber, 1 = mirror).

    Defaults for an office-like room at 60 GHz, at normal incidence. A lossless half-space of
    relative permittivity eps reflects |Gamma| = (sqrt(eps) - 1) / (sqrt(eps) + 1): about 0.25
    for plasterboard or wood (eps ~ 2.5-3), about 0.4 for concrete or screed (eps ~ 5-6.5).
    Paint, roughness of a fraction of the 5 mm wavelength and layer structure scatter or
    absorb part of the rest, so 0.35 (9 dB reflection loss) stands for walls and floor, and
    0.25 (12 dB) for a ceiling of porous mineral-fibre tiles. Obstacles are taken as metal
    furniture (shelves, cabinets): 0.8. Glass or bare metal walls need larger values.
    """

    walls: Fraction = 0.35
    floor: Fraction = 0.35
    ceiling: Fraction = 0.25
    obstacles: Fraction = 0.8


#: Largest room side (m): an indoor room; the map-wide grids of the localisers scale with area.
MAX_ROOM_SIDE_M = 100.0


class RoomConfig(Strict):
    size: PosVec3 = [5.0, 5.0, 4.0]
    obstacles: list[BoxConfig] = []
    surfaces: SurfacesConfig = SurfacesConfig()

    @field_validator("size")
    @classmethod
    def _indoor(cls, size: list[float]) -> list[float]:
        if max(size) > MAX_ROOM_SIDE_M:
            raise PydanticCustomError(
                "room_size",
                "every side must be at most {limit} m (an indoor room), got {size}",
                {"limit": MAX_ROOM_SIDE_M, "size": size},
            )
        return size


class ReflectorTypeConfig(Strict):
    """One reflector type. ``kind`` picks the RCS model; each needs its own size field."""

    kind: Literal["trihedral", "sphere", "luneburg", "van_atta", "point"]
    edge_m: PositiveFloat | None = None
    diameter_m: PositiveFloat | None = None
    elements: Annotated[int, Field(gt=0)] | None = None
    element_area_m2: PositiveFloat | None = None
    rcs_dbsm: Annotated[float, Field(ge=-60, le=60)] | None = None
    half_angle_deg: Annotated[float, Field(gt=0, le=180)] | None = None
    cutoff_deg: Annotated[float, Field(gt=0, le=180)] | None = None

    _needs = {
        "trihedral": ("edge_m",),
        "sphere": ("diameter_m",),
        "luneburg": ("diameter_m",),
        "van_atta": ("elements", "element_area_m2"),
        "point": ("rcs_dbsm",),
    }

    @model_validator(mode="after")
    def _sizes(self) -> ReflectorTypeConfig:
        missing = [f for f in self._needs[self.kind] if getattr(self, f) is None]
        if missing:
            raise PydanticCustomError(
                "reflector",
                "kind {kind} needs {fields}",
                {"kind": self.kind, "fields": ", ".join(missing)},
            )
        return self

    def pattern_angles(self) -> tuple[float | None, float]:
        """(-3 dB half angle, cutoff) in degrees, with the kind's defaults.

        Corner reflectors and Van Atta arrays only retro-reflect around their axis (about
        +-40 deg for a trihedral); spheres, points and Luneburg lenses are taken as
        omnidirectional over the lower hemisphere they face.
        """
        defaults = {"trihedral": (40.0, 90.0), "van_atta": (45.0, 90.0)}
        half, cutoff = defaults.get(self.kind, (None, 180.0))
        return (self.half_angle_deg or half, self.cutoff_deg or cutoff)


class ReflectorPlacement(Strict):
    position: Vec3
    type: str
    axis: Vec3 | None = Field(
        default=None,
        description="boresight unit vector; default points at the room centre at radar height",
    )


class ReflectorsConfig(Strict):
    types: dict[str, ReflectorTypeConfig] = {
        "A": ReflectorTypeConfig(kind="trihedral", edge_m=0.05)
    }
    layout: list[ReflectorPlacement] = []

    @model_validator(mode="after")
    def _known_types(self) -> ReflectorsConfig:
        if not self.types:
            raise PydanticCustomError("types", "at least one reflector type is needed", {})
        for i, r in enumerate(self.layout):
            if r.type not in self.types:
                raise PydanticCustomError(
                    "type",
                    "layout[{i}].type {t} is not one of the types {known}",
                    {"i": i, "t": repr(r.type), "known": _fmt(sorted(self.types))},
                )
        return self
