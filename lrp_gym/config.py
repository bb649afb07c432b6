"""Validated scenario schema: room, reflectors, radar, robot, tracking, localisation and task.

Load with :func:`load_scenario` (YAML file) or :meth:`ScenarioConfig.from_dict`; save with
:func:`save_scenario`. Unknown keys are rejected and every problem is reported at once, each
naming its field, as a :class:`ScenarioError`.
"""

from __future__ import annotations

import importlib.resources
import math
import sys
from pathlib import Path
from typing import Annotated, Any, Literal

import yaml
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from lrp_gym.scenario_yaml import load_yaml
from lrp_gym.waveform import FmcwParameters


def _configs_dir() -> Path:
    """The shipped configs: package data of an installed wheel, else the checkout's configs/.

    The wheel copies the top-level ``configs/`` into ``lrp_gym/configs`` (see pyproject.toml),
    so there is one copy to edit; editable installs and source checkouts read it in place.
    """
    packaged = Path(str(importlib.resources.files("lrp_gym") / "configs"))
    return packaged if packaged.is_dir() else Path(__file__).resolve().parent.parent / "configs"


CONFIGS_DIR = _configs_dir()
SCENARIOS_DIR = CONFIGS_DIR / "scenarios"


class ScenarioError(ValueError):
    """A scenario failed validation; ``problems`` lists one message per bad field."""

    def __init__(self, problems: list[str], source: str | None = None) -> None:
        self.problems = problems
        self.source = source
        head = f"invalid scenario{f' {source}' if source else ''}"
        super().__init__(head + ":\n" + "\n".join(f"  - {p}" for p in problems))


def _fmt(value: Any) -> str:
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_fmt(v) for v in value) + "]"
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return repr(value) if isinstance(value, str) else str(value)


def _vector(n: int, positive: bool = False, what: str = "numbers"):
    """A list of ``n`` finite floats, with a message that shows what was given."""

    def check(value: Any) -> list[float]:
        kind = f"{n} positive {what}" if positive else f"{n} {what}"
        ok = isinstance(value, (list, tuple)) and len(value) == n
        if ok:
            try:
                out = [float(v) for v in value]
            except (TypeError, ValueError):
                ok = False
            else:
                if any(isinstance(v, bool) for v in value) or not all(map(math.isfinite, out)):
                    ok = False
                elif positive and any(v <= 0 for v in out):
                    ok = False
        if not ok:
            raise PydanticCustomError(
                "vector", "expected {kind}, got {got}", {"kind": kind, "got": _fmt(value)}
            )
        return out

    from pydantic import BeforeValidator

    return Annotated[list[float], BeforeValidator(check)]


Vec2 = _vector(2)
Vec3 = _vector(3)
PosVec3 = _vector(3, positive=True)
Pose = _vector(3, what="numbers (x_m, y_m, theta_rad)")
PositiveFloat = Annotated[float, Field(gt=0, allow_inf_nan=False)]
NonNegFloat = Annotated[float, Field(ge=0, allow_inf_nan=False)]
Probability = Annotated[float, Field(gt=0, lt=1, allow_inf_nan=False)]
Fraction = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_default=True)


# --------------------------------------------------------------------------- room
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


# --------------------------------------------------------------------------- reflectors
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


# --------------------------------------------------------------------------- radar
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


# --------------------------------------------------------------------------- robot
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


# --------------------------------------------------------------------------- tracking
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


# --------------------------------------------------------------------------- localisation
class MotionNoiseConfig(Strict):
    """AMCL's motion model: the paper's sigmas on turned angle and distance, plus alphas."""

    sigma_turn_deg: NonNegFloat = 5.0
    sigma_distance_m: NonNegFloat = 0.05
    alphas: Annotated[list[NonNegFloat], Field(min_length=4, max_length=4)] = [0.0, 0.0, 0.0, 0.0]


class LocalizationConfig(Strict):
    method: Literal["amcl", "lut", "grid"] = "amcl"
    lut_resolution_m: PositiveFloat = 0.075
    lut_grid_m: PositiveFloat = 0.025
    # Histogram filter (method grid, lrp_gym.localization.grid): cell size in x, y and heading.
    grid_cell_m: PositiveFloat = 0.05
    grid_cell_deg: Annotated[float, Field(gt=0.0, le=180.0)] = 5.0
    initial_particles: Annotated[int, Field(ge=10)] = 10000
    min_particles: Annotated[int, Field(ge=10)] = 200
    max_particles: Annotated[int, Field(ge=10)] = 10000
    kld_error: Probability = 0.05
    kld_quantile: Probability = 0.99
    kld_bin_m: PositiveFloat = 0.1
    kld_bin_deg: PositiveFloat = 10.0
    motion_noise: MotionNoiseConfig = MotionNoiseConfig()
    measurement_std_m: PositiveFloat = 0.075
    measurements: Literal["detections", "tracks"] = Field(
        default="detections",
        description="what AMCL weighs: every RCS-gated detection, or the tracked fingerprint",
    )
    recovery_measurements: Literal["detections", "tracks"] = Field(
        default="tracks",
        description="what augmented MCL's fit statistic scores: the measurements AMCL weighs, "
        "or the tracker's persistent tracks updated in this frame (default: one-frame "
        "clutter does not keep a lost filter's fit up)",
    )
    clutter_probability: Fraction = 0.2
    structure_probability: Fraction = 0.6
    doppler_std_mps: NonNegFloat = Field(
        default=0.15,
        description="std of a return's measured radial velocity in AMCL's likelihood (heading "
        "evidence while moving); 0 weighs the distances only",
    )
    doppler_outlier_probability: Fraction = 0.1
    detection_probability: Fraction = Field(
        default=0.0,
        description="probability that a reflector yields a detection; > 0 penalises poses "
        "whose reflectors no measured distance matches (negative information)",
    )
    global_proposal: bool = Field(
        default=True,
        description="draw the global start and recovery particles from a map-wide grid of the "
        "frame likelihood, and test whether the cloud has lost the robot",
    )
    global_grid_m: PositiveFloat = 0.1
    likelihood_exponent: Annotated[float, Field(gt=0.0, le=1.0)] = Field(
        default=0.5,
        description="power of each frame's likelihood (< 1 tempers it: frames' errors are "
        "correlated, so their product would overcount the evidence)",
    )
    mode_min_particles: Annotated[int, Field(ge=0)] = Field(
        default=100,
        description="particles every posterior mode keeps through resampling (weighted by its "
        "mass), so that a minority mode survives until the evidence decides; 0: plain resampling",
    )
    lost_drift_nats: NonNegFloat = 4.0
    lost_threshold_nats: PositiveFloat = 8.0
    lost_restart_nats: PositiveFloat = 20.0
    resample_ess_ratio: Fraction = 0.5
    alpha_slow: Fraction = 0.02
    alpha_fast: Fraction = 0.3
    max_random_fraction: Fraction = 0.25
    recovery_fit_ratio: Annotated[float, Field(gt=0.0, le=1.0)] = 0.8
    estimator: Literal["best_k", "cluster"] = "cluster"
    estimate_best_k: Annotated[int, Field(ge=1)] = 20
    estimate_radius_m: PositiveFloat = 0.15
    init: Literal["uniform", "gaussian"] = "uniform"
    init_std: Vec3 = [0.3, 0.3, 0.35]
    converged_std_m: PositiveFloat = 0.25
    converged_mass: Annotated[float, Field(gt=0.0, le=1.0)] = 0.9

    @model_validator(mode="after")
    def _counts(self) -> LocalizationConfig:
        if not self.min_particles <= self.max_particles:
            raise PydanticCustomError(
                "particles",
                "min_particles ({a}) must not exceed max_particles ({b})",
                {"a": self.min_particles, "b": self.max_particles},
            )
        return self


# --------------------------------------------------------------------------- placement
class PlacementConfig(Strict):
    grid_m: PositiveFloat = 0.025
    clearance_m: NonNegFloat = 0.0
    separation_m: PositiveFloat = 0.3
    tolerance_m: PositiveFloat | None = None
    min_spacing_m: NonNegFloat = 1.0
    wall_distance_m: NonNegFloat = 0.3
    constraint_tolerance_m: NonNegFloat = 0.1
    # Layout search: every candidate is scored on the coarse search grid, the best
    # ``refine_top`` again on ``grid_m``.
    candidates: Annotated[int, Field(ge=1)] = 500
    search_grid_m: PositiveFloat = 0.1
    refine_top: Annotated[int, Field(ge=1)] = 8


# --------------------------------------------------------------------------- task
class GoalTaskConfig(Strict):
    """Sampled goal tasks: start-to-goal distance bounds (checked against the room)."""

    min_distance_m: PositiveFloat = 1.0
    max_distance_m: PositiveFloat = 4.0
    waypoint_spacing_m: PositiveFloat = 0.5


class RewardConfig(Strict):
    progress: NonNegFloat = 1.0
    time: NonNegFloat = 0.01
    collision: NonNegFloat = 5.0
    goal: NonNegFloat = 5.0


#: Observation types shipped in ``lrp_gym.envs.observations`` (more may be registered there).
OBSERVATION_TYPES = ("estimated", "oracle", "dict")


class ObservationConfig(Strict):
    """Which observation type the env builds (see ``lrp_gym.envs.observations``)."""

    type: str = "estimated"
    n_waypoints: Annotated[int, Field(ge=1, le=20)] = 3

    @field_validator("type")
    @classmethod
    def _registered(cls, v: str) -> str:
        # The registry is consulted only once loaded (it imports this module); user types are
        # registered there before a scenario names them.
        obs = sys.modules.get("lrp_gym.envs.observations")
        known = sorted(set(OBSERVATION_TYPES) | set(getattr(obs, "OBSERVATION_TYPES", {})))
        if v not in known:
            raise PydanticCustomError(
                "choice",
                "unknown observation type {v}; known: {known}",
                {"v": repr(v), "known": ", ".join(known)},
            )
        return v


class EnvConfig(Strict):
    """Environment settings: observation type, collision sub-steps, render size."""

    observation: ObservationConfig = ObservationConfig()
    substeps: Annotated[int, Field(ge=1, le=50)] = 4
    render_size_px: Annotated[int, Field(ge=64, le=2048)] = 480


class TaskConfig(Strict):
    mode: Literal["path", "goal"] = "path"
    path: list[Vec2] = []
    frame_period_s: PositiveFloat = 0.25
    goal_tolerance_m: PositiveFloat = 0.25
    goal: GoalTaskConfig = GoalTaskConfig()
    rewards: RewardConfig = RewardConfig()

    @model_validator(mode="after")
    def _path_needed(self) -> TaskConfig:
        if self.mode == "path" and len(self.path) < 2:
            raise PydanticCustomError("path", "mode 'path' needs at least 2 waypoints in path", {})
        return self


# --------------------------------------------------------------------------- perturbations
# Robustness perturbations (see lrp_gym.perturbations). Each has a ``severity`` in [0, 1]; the
# physical parameters left at None are derived from it (documented per class there).
Severity = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]
FrameCount = Annotated[int, Field(ge=0, le=100_000)]


class _PerturbationBase(Strict):
    severity: Severity = 0.5


class ShadowingConfig(_PerturbationBase):
    """Reflectors hidden for ``frames`` frames by a static obstacle or a walking person."""

    mode: Literal["static", "person"] = "static"
    frames: Annotated[int, Field(ge=1, le=100_000)] | None = None
    reflectors: Annotated[int, Field(ge=1, le=1000)] = 1
    start_frames: Annotated[list[FrameCount], Field(min_length=2, max_length=2)] = [3, 20]
    person_size_m: PosVec3 = [0.5, 0.5, 1.8]


class MissedDetectionsConfig(_PerturbationBase):
    probability: Fraction | None = None


class ClutterConfig(_PerturbationBase):
    count: Annotated[int, Field(ge=0, le=10_000)] | None = None
    rcs_spread_db: NonNegFloat = 3.0


class DisplacedReflectorConfig(_PerturbationBase):
    shift_m: NonNegFloat | None = None
    reflectors: Annotated[int, Field(ge=1, le=1000)] = 1


class OdometrySlipConfig(_PerturbationBase):
    slip: Annotated[float, Field(gt=-1, le=10, allow_inf_nan=False)] | None = None
    heading_bias_dps: Annotated[float, Field(ge=-3600, le=3600, allow_inf_nan=False)] | None = None


class KidnappingConfig(_PerturbationBase):
    frames: Annotated[list[FrameCount], Field(min_length=2, max_length=2)] = [5, 15]
    min_jump_m: NonNegFloat | None = None


class InterferenceConfig(_PerturbationBase):
    burst_probability: Fraction | None = None
    burst_frames: Annotated[int, Field(ge=1, le=100_000)] = 3
    detections_per_frame: Annotated[int, Field(ge=0, le=10_000)] | None = None
    rcs_spread_db: NonNegFloat = 6.0


class IncidenceAngleConfig(_PerturbationBase):
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

    def active(self) -> dict[str, BaseModel]:
        """The perturbations that are on, by name."""
        return {k: v for k in type(self).model_fields if (v := getattr(self, k)) is not None}


# --------------------------------------------------------------------------- scenario
class ScenarioConfig(Strict):
    """A complete scenario. Every section has defaults; ``reflectors.layout`` must be given."""

    name: str = "scenario"
    description: str = ""
    room: RoomConfig = RoomConfig()
    reflectors: ReflectorsConfig = ReflectorsConfig()
    radar: RadarConfig = RadarConfig()
    robot: RobotConfig = RobotConfig()
    tracking: TrackingConfig = TrackingConfig()
    localization: LocalizationConfig = LocalizationConfig()
    placement: PlacementConfig = PlacementConfig()
    task: TaskConfig = TaskConfig(mode="goal")
    env: EnvConfig = EnvConfig()
    perturbations: PerturbationsConfig = PerturbationsConfig()

    @model_validator(mode="after")
    def _cross_checks(self) -> ScenarioConfig:
        from lrp_gym.config_checks import cross_problems

        problems = list(cross_problems(self))
        if problems:
            raise PydanticCustomError("cross", "\n".join(problems), {})
        return self

    # --- construction ------------------------------------------------------------
    @classmethod
    def from_dict(cls, data: Any, source: str | None = None) -> ScenarioConfig:
        """Validate a mapping; raise :class:`ScenarioError` listing every problem."""
        if not isinstance(data, dict):
            raise ScenarioError(
                [f"expected a mapping at the top level, got {type(data).__name__}"], source
            )
        try:
            return cls.model_validate(data)
        except ValidationError as exc:
            raise ScenarioError(format_errors(exc), source) from None

    def to_dict(self) -> dict[str, Any]:
        return self.model_dump(mode="json", exclude_none=True)

    def with_overrides(self, overrides: dict[str, Any]) -> ScenarioConfig:
        """A copy with nested keys replaced, e.g. ``{"radar": {"noise": False}}``."""
        return ScenarioConfig.from_dict(deep_merge(self.to_dict(), overrides), self.name)

    # --- derived runtime objects -----------------------------------------------------
    def fmcw(self) -> FmcwParameters:
        return self.radar.fmcw()


def deep_merge(base: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """Recursively merge ``overrides`` into a copy of ``base`` (dicts merge, others replace)."""
    out = dict(base)
    for key, value in overrides.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = deep_merge(out[key], value)
        else:
            out[key] = value
    return out


def format_errors(exc: ValidationError) -> list[str]:
    """One ``field.path: message`` line per validation problem."""
    problems: list[str] = []
    for err in exc.errors():
        loc = ".".join(f"[{p}]" if isinstance(p, int) else str(p) for p in err["loc"]).replace(
            ".[", "["
        )
        msg = err["msg"]
        if err["type"] == "extra_forbidden":
            msg = "unknown key (not part of the schema)"
        elif err["type"] == "missing":
            msg = "required field is missing"
        elif err["type"] == "literal_error":
            msg = f"{msg}, got {_fmt(err.get('input'))}"
        elif (
            err["type"] not in {"vector", "box", "reflector", "cells", "cross", "choice"}
            and "input" in err
        ):
            got = err["input"]
            if not isinstance(got, (dict, list)):
                msg = f"{msg}, got {_fmt(got)}"
        if err["type"] == "cross":
            problems.extend(msg.split("\n"))
            continue
        problems.append(f"{loc}: {msg}" if loc else msg)
    return problems


def load_scenario(source: str | Path | dict[str, Any] | ScenarioConfig) -> ScenarioConfig:
    """Load and validate a scenario.

    Parameters
    ----------
    source : path, name, dict or ScenarioConfig
        A YAML file, the name of a scenario shipped in ``configs/scenarios`` (e.g.
        ``"ipin2023"``), a mapping, or an already validated config.

    Raises
    ------
    ScenarioError
        With one message per problem, each naming the field.
    """
    if isinstance(source, ScenarioConfig):
        return source
    if isinstance(source, dict):
        return ScenarioConfig.from_dict(source)
    path = Path(source)
    if not path.exists() and not path.suffix and (SCENARIOS_DIR / f"{path}.yaml").exists():
        path = SCENARIOS_DIR / f"{path}.yaml"
    if not path.exists():
        raise ScenarioError([f"file not found: {path}"], str(path))
    if path.is_dir():
        raise ScenarioError([f"expected a YAML file, got a directory: {path}"], str(path))
    if not path.is_file():  # a FIFO or device would block or never end
        raise ScenarioError(
            [f"expected a regular YAML file, got a special file: {path}"], str(path)
        )
    try:
        data = load_yaml(path.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError, OSError) as exc:
        raise ScenarioError([f"cannot read YAML: {exc}".replace("\n", " ")], str(path)) from None
    except ValueError as exc:
        raise ScenarioError([f"cannot read YAML: {exc}"], str(path)) from None
    return ScenarioConfig.from_dict(data, str(path))


def save_scenario(cfg: ScenarioConfig, path: str | Path, header: str = "") -> Path:
    """Write a scenario as YAML atomically (a temporary file renamed into place)."""
    path = Path(path)
    text = yaml.safe_dump(cfg.to_dict(), sort_keys=False, default_flow_style=None, width=100)
    if header:
        text = "".join(f"# {line}\n" if line else "#\n" for line in header.splitlines()) + text
    tmp = path.with_name(path.name + ".tmp")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)
    return path
