"""Schema of the localisers (AMCL, grid) and their measurement model."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import (
    Field,
    model_validator,
)
from pydantic_core import PydanticCustomError

from lrp_gym.config.base import Fraction, NonNegFloat, PositiveFloat, Probability, Strict, Vec3
from lrp_gym.config.room_changes import ClutterMapConfig, ReflectorMonitorConfig

__all__ = ["ClutterMapConfig", "LocalizationConfig", "MotionNoiseConfig", "ReflectorMonitorConfig"]


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
    measurement_std_m: PositiveFloat = Field(
        default=0.03,
        description="range std of the weights' likelihood (m): the chain's error on a "
        "reflector's distance (68 % within 2-3 cm, docs/trust.md), not the 7.5 cm range "
        "resolution; a wider one lets a wrong pose fit merged returns as well as the truth",
    )
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
    clutter_probability: Fraction = Field(
        default=0.5,
        description="share of measured distances that neither a reflector nor the room "
        "explains (uniform in range); a heavy outlier class, because unmapped scatterers "
        "persist from frame to frame (docs/robustness.md)",
    )
    structure_probability: Fraction = 0.6
    ghost_probability: Fraction = Field(
        default=0.1,
        description="probability that a measured distance is a reflector seen via a wall or "
        "the ceiling (its image source); with structure_probability at most 1",
    )
    doppler_std_mps: NonNegFloat = Field(
        default=0.15,
        description="std of a return's measured radial velocity in AMCL's likelihood (heading "
        "evidence while moving); 0 weighs the distances only",
    )
    doppler_outlier_probability: Fraction = 0.1
    detection_probability: Fraction = Field(
        default=0.8,
        description="probability that a reflector yields a detection; > 0 penalises poses "
        "whose reflectors no measured distance (of any type) matches (negative information; "
        "the radar delivers a visible trihedral in about 95 % of frames, 84 % among strong "
        "scatterers); 0 leaves the term out",
    )
    reflector_visibility: bool = Field(
        default=True,
        description="weigh each reflector by the radar's probability of detecting it from the "
        "particle's position (obstacles on the line of sight, pattern cutoff, range, SNR from "
        "the link budget): a hidden reflector explains no distance and its silence costs "
        "nothing; rooms where every reflector is detected everywhere are unaffected",
    )
    detection_survey_poses: Annotated[int, Field(ge=0)] = Field(
        default=200,
        description="with reflector_visibility: poses of a calibration survey (radar frames "
        "at random free poses, fixed seed) that measures how often the radar delivers each "
        "reflector in view; a reflector delivered less often than detection_probability gets "
        "its measured rate instead (never more: misses repeat along the path), also where its "
        "link budget detects it everywhere (masked by stronger returns); 0: no survey",
    )
    return_mix_survey_poses: Annotated[int, Field(ge=0)] = Field(
        default=200,
        description="radar frames at random free poses (fixed seed) from which the "
        "structure_probability and ghost_probability are measured: the shares of the "
        "tracker's RCS-window returns that come from the room's surfaces and from reflectors "
        "via its faces (lrp_gym.localization.return_mix); used where the radar returns more "
        "ghosts than ghost_probability (omnidirectional reflectors), else the set ones; "
        "0: always as set",
    )
    ghost_weights: Literal["surveyed", "uniform"] = Field(
        default="surveyed",
        description="with a return-mix survey (return_mix_survey_poses > 0): share "
        "ghost_probability among the predicted ghosts by how often the survey found each "
        "(a few strong ghosts, many weak ones never seen); uniform: equally",
    )
    global_proposal: bool = Field(
        default=True,
        description="draw the global start and recovery particles from a map-wide grid of the "
        "frame likelihood, and test whether the cloud has lost the robot",
    )
    global_grid_m: PositiveFloat = Field(
        default=0.1,
        description="spacing of the lost test's and recovery's map-wide grid (m); the global "
        "start's grid is twice as fine unless start_grid_m is given",
    )
    start_grid_m: PositiveFloat | None = Field(
        default=None,
        description="spacing of the global start's grid (m); None: global_grid_m / 2",
    )
    likelihood_exponent: Annotated[float, Field(gt=0.0, le=1.0)] = Field(
        default=0.5,
        description="power of each frame's likelihood (< 1 tempers it: frames' errors are "
        "correlated, so their product would overcount the evidence)",
    )
    likelihood_correlation_m: PositiveFloat | None = Field(
        default=0.03,
        description="length (m) over which the frames' range errors decorrelate along the "
        "path, rho = exp(-d / L): a frame d after the last weighs likelihood_exponent x "
        "(1 - rho) / (1 + rho), so a robot at the same spot (static clutter's returns repeat "
        "there) does not count the same evidence every frame; 0.03: the signal chain's "
        "errors decorrelate within 6-10 cm; None: every frame weighs likelihood_exponent",
    )
    mode_min_particles: Annotated[int, Field(ge=0)] = Field(
        default=300,
        description="particles every posterior mode keeps through resampling (weighted by its "
        "mass), so that a minority mode survives until the evidence decides; 0: plain resampling",
    )
    lost_drift_nats: NonNegFloat = 4.0
    lost_drift_per_distance_nats: NonNegFloat = Field(
        default=0.4,
        description="the lost test's drift per measured distance: a frame's drift is "
        "max(lost_drift_nats, this x distances), because the best grid cell's chance fit "
        "grows with the distances weighed (a right cloud read as lost in rooms with many "
        "reflector-like returns)",
    )
    lost_test_clutter_probability: Fraction | None = Field(
        default=0.2,
        description="the clutter probability of the model that the lost test (and the "
        "recovery grid) weighs with; None: clutter_probability. Lighter than the weights' "
        "outlier class: a heavy one shrinks a lost cloud's deficit per frame below the "
        "test's drift (calibrated with 0.2), and a kidnap goes unnoticed for frames",
    )
    lost_test_std_m: PositiveFloat | None = Field(
        default=None,
        description="range std of the model that the lost test (and the recovery grid) weighs "
        "with; None: measurement_std_m with the lost grid's quantisation added (cell^2 / 12 "
        "in variance, 2.9 cm for 10 cm cells). The test weighs cell centres up to half a cell "
        "from the robot: with the weights' std alone a right cloud reads as lost",
    )
    lost_alternative_drift_nats: NonNegFloat | None = Field(
        default=1.0,
        description="drift per frame of the lost test's second statistic: a filter over the "
        "grid's cells against the cloud (lrp_gym.localization.grid_alternative), which notices "
        "a wrong cloud that the truth beats by a few nats in every frame; None: leave it out",
    )
    lost_alternative_drift_per_distance_nats: NonNegFloat = Field(
        default=0.1,
        description="the second statistic's drift per measured distance: a frame's drift is "
        "max(lost_alternative_drift_nats, this x distances), because chance fits elsewhere "
        "on the map grow with the distances weighed, as for the first statistic",
    )
    lost_threshold_nats: PositiveFloat = 8.0
    lost_restart_nats: PositiveFloat = 20.0
    lost_test_every: Annotated[int, Field(ge=1)] = Field(
        default=1,
        description="while the estimate is settled, the lost test quiet, no recovery under "
        "way and the cloud's likelihood close to the last best grid cell, evaluate the lost "
        "test's map-wide grid (the largest per-frame cost) only every this many frames; "
        "1 (default): every frame; 4 keeps the trust rows but lets kidnaps go unnoticed "
        "longer (docs/vector.md)",
    )
    resample_ess_ratio: Fraction = 0.5
    alpha_slow: Fraction = 0.02
    alpha_fast: Fraction = 0.3
    max_random_fraction: Fraction = 0.25
    slip_adaptive: bool = Field(
        default=False,
        description="inflate the motion noise while the settled estimate keeps moving away "
        "from where the odometry alone would put it (wheel slip; lrp_gym.localization.slip)",
    )
    slip_max_inflation: Annotated[float, Field(ge=1.0, le=100.0)] = 4.0
    recovery_fit_ratio: Annotated[float, Field(gt=0.0, le=1.0)] = 0.8
    estimator: Literal["best_k", "cluster"] = "cluster"
    estimate_best_k: Annotated[int, Field(ge=1)] = 20
    estimate_radius_m: PositiveFloat = 0.15
    init: Literal["uniform", "gaussian"] = "uniform"
    init_std: Vec3 = [0.3, 0.3, 0.35]
    converged_std_m: PositiveFloat = 0.25
    converged_mass: Annotated[float, Field(gt=0.0, le=1.0)] = Field(
        default=0.99,
        description="the confidence at which the estimate is reported converged (info, "
        "observation, the trust metrics): the localiser's claim that it is right. 0.99: "
        "converged steps at 0.90-0.99 were wrong 27-42 % of the time on generated rooms "
        "(docs/trust.md, session 26)",
    )
    settled_mass: Annotated[float, Field(gt=0.0, le=1.0)] = Field(
        default=0.9,
        description="the confidence at which the localiser's own consumers take the estimate "
        "as settled: the tracker's map-aided prior, the clutter map, the reflector monitor, "
        "the slip estimate and the lost test's quiet frames. They need a usable pose often "
        "more than a guarantee: at 0.99 the clutter map learned too rarely and the patrol "
        "under clutter failed (docs/trust.md, session 26)",
    )
    reflector_monitor: ReflectorMonitorConfig = ReflectorMonitorConfig()
    clutter_map: ClutterMapConfig = ClutterMapConfig()

    @property
    def start_cell_m(self) -> float:
        """The global start's grid spacing: ``start_grid_m``, or ``global_grid_m / 2``."""
        return self.global_grid_m / 2.0 if self.start_grid_m is None else self.start_grid_m

    @model_validator(mode="after")
    def _counts(self) -> LocalizationConfig:
        if not self.min_particles <= self.max_particles:
            raise PydanticCustomError(
                "particles",
                "min_particles ({a}) must not exceed max_particles ({b})",
                {"a": self.min_particles, "b": self.max_particles},
            )
        if self.structure_probability + self.ghost_probability > 1.0:
            raise PydanticCustomError(
                "mixture",
                "structure_probability ({a}) + ghost_probability ({b}) must not exceed 1",
                {"a": self.structure_probability, "b": self.ghost_probability},
            )
        return self
