"""Validated scenario schema: room, reflectors, radar, robot, tracking, localisation and task.

Load with :func:`load_scenario` (YAML file) or :meth:`ScenarioConfig.from_dict`; save with
:func:`save_scenario`. Unknown keys are rejected and every problem is reported at once, each
naming its field, as a :class:`ScenarioError`.
"""

from lrp_gym.config.base import (
    CONFIGS_DIR,
    SCENARIOS_DIR,
    Fraction,
    NonNegFloat,
    Pose,
    PositiveFloat,
    PosVec3,
    Probability,
    ScenarioError,
    Strict,
    Vec2,
    Vec3,
)
from lrp_gym.config.localization import (
    ClutterMapConfig,
    LocalizationConfig,
    MotionNoiseConfig,
    ReflectorMonitorConfig,
)
from lrp_gym.config.perturbations import (
    ClutterConfig,
    DisplacedReflectorConfig,
    FrameCount,
    IncidenceAngleConfig,
    InterferenceConfig,
    KidnappingConfig,
    MissedDetectionsConfig,
    OdometrySlipConfig,
    PerturbationsConfig,
    Severity,
    ShadowingConfig,
)
from lrp_gym.config.radar import CfarConfig, RadarConfig, RequirementsConfig
from lrp_gym.config.robot import OdometryNoiseConfig, RobotConfig
from lrp_gym.config.room import (
    MAX_ROOM_SIDE_M,
    BoxConfig,
    ReflectorPlacement,
    ReflectorsConfig,
    ReflectorTypeConfig,
    RoomConfig,
    SurfacesConfig,
)
from lrp_gym.config.scenario import (
    ScenarioConfig,
    deep_merge,
    format_errors,
    load_scenario,
    save_scenario,
)
from lrp_gym.config.task import (
    OBSERVATION_TYPES,
    EnvConfig,
    GoalTaskConfig,
    ObservationConfig,
    PlacementConfig,
    RewardConfig,
    TaskConfig,
)
from lrp_gym.config.tracking import TrackingConfig

__all__ = [
    "BoxConfig",
    "CONFIGS_DIR",
    "CfarConfig",
    "ClutterConfig",
    "DisplacedReflectorConfig",
    "EnvConfig",
    "Fraction",
    "FrameCount",
    "GoalTaskConfig",
    "IncidenceAngleConfig",
    "InterferenceConfig",
    "KidnappingConfig",
    "LocalizationConfig",
    "ReflectorMonitorConfig",
    "ClutterMapConfig",
    "MAX_ROOM_SIDE_M",
    "MissedDetectionsConfig",
    "MotionNoiseConfig",
    "NonNegFloat",
    "OBSERVATION_TYPES",
    "ObservationConfig",
    "OdometryNoiseConfig",
    "OdometrySlipConfig",
    "PerturbationsConfig",
    "PlacementConfig",
    "PosVec3",
    "Pose",
    "PositiveFloat",
    "Probability",
    "RadarConfig",
    "ReflectorPlacement",
    "ReflectorTypeConfig",
    "ReflectorsConfig",
    "RequirementsConfig",
    "RewardConfig",
    "RobotConfig",
    "RoomConfig",
    "SCENARIOS_DIR",
    "ScenarioConfig",
    "ScenarioError",
    "Severity",
    "ShadowingConfig",
    "Strict",
    "SurfacesConfig",
    "TaskConfig",
    "TrackingConfig",
    "Vec2",
    "Vec3",
    "deep_merge",
    "format_errors",
    "load_scenario",
    "save_scenario",
]
