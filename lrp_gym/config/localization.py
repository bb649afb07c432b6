"""Schema of the localisers (AMCL, grid) and their measurement model."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import (
    Field,
    model_validator,
)
from pydantic_core import PydanticCustomError

from lrp_gym.config.base import Fraction, NonNegFloat, PositiveFloat, Probability, Strict, Vec3


class MotionNoiseConfig(Strict):
    """AMCL's motion model: the paper's sigmas on turned angle and distance, plus alphas."""

    sigma_turn_deg: NonNegFloat = 5.0
    sigma_distance_m: NonNegFloat = 0.05
    alphas: Annotated[list[NonNegFloat], Field(min_length=4, max_length=4)] = [0.0, 0.0, 0.0, 0.0]


class ReflectorMonitorConfig(Strict):
    """Which mapped reflector is missing or moved (lrp_gym.localization.reflector_monitor)."""

    enabled: bool = True
    drop_suspects: bool = Field(
        default=True,
        description="leave suspected reflectors out of the localiser's measurement model",
    )
    window_frames: Annotated[int, Field(ge=1, le=10_000)] = 30
    min_visible_frames: Annotated[int, Field(ge=1, le=10_000)] = 12
    suspect_share: Annotated[float, Field(gt=0.0, le=1.0)] = Field(
        default=0.25,
        description="a reflector missing in this share of its visible frames (and, by "
        "excess_z, more often than its peers) is a suspect",
    )
    clear_share: Fraction = Field(
        default=0.1,
        description="a suspect whose miss share falls below this (or to its peers') is cleared",
    )
    excess_z: NonNegFloat = Field(
        default=4.0,
        description="a reflector is a suspect on misses only if its miss share exceeds the "
        "other visible reflectors' in the same frames (their common miss rate) by this many "
        "standard errors (one-sided two-proportion z-test; 0: by anything): dropped "
        "detections or a covered radar hit every reflector alike. High because the test is "
        "repeated every frame of an episode",
    )
    gate_sigmas: PositiveFloat = 3.0
    bias_m: PositiveFloat | None = Field(
        default=None,
        description="a reflector whose nearest return is on average this far from its "
        "predicted distance (same side) is a suspect too; None (default): off, the "
        "displacement test does this with the pose error removed",
    )
    displacement_test: Literal["likelihood", "parity"] = Field(
        default="likelihood",
        description="how a small move is found: 'likelihood', a likelihood-ratio test over a "
        "grid of displacements with every nearby return a candidate "
        "(lrp_gym.localization.displacement_glrt); 'parity', the parity-space test on the "
        "nearest returns, pose error removed (lrp_gym.localization.displacement_test; its "
        "settings were chi2 20, lead 10, window 50 frames)",
    )
    displacement_chi2: PositiveFloat | None = Field(
        default=25.0,
        description="a reflector whose displacement statistic (twice the log-likelihood "
        "ratio of its best-fitting move against none; chi-square with 2 dof for the parity "
        "test) reaches this is a suspect; None: off",
    )
    displacement_lead: NonNegFloat = Field(
        default=20.0,
        description="... and exceeds every other reflector's statistic by this (one moved "
        "reflector spreads into the others' statistics)",
    )
    displacement_max_m: PositiveFloat = Field(
        default=0.35,
        description="likelihood test: the largest move it fits (farther moves take the "
        "reflector's returns out of the miss gate, and the miss count names them)",
    )
    displacement_detection_probability: Probability = Field(
        default=0.9,
        description="likelihood test: probability that a reflector's own return is among a "
        "frame's distances",
    )
    displacement_clutter_per_m: PositiveFloat = Field(
        default=3.0,
        description="likelihood test: density of the other reflector-like distances around a "
        "reflector's, per metre (about 3 on the patrol: structure, ghosts, other reflectors)",
    )
    displacement_doppler_std_mps: NonNegFloat = Field(
        default=0.15,
        description="likelihood test: std of a return's radial velocity about the one the "
        "reflector's line of sight and the robot's wheel speed predict; a return's weight as "
        "the reflector's own is its density there over a static scatterer's (the room's "
        "returns near the reflector's distance come from other directions, so they move at "
        "other radial velocities); 0 weighs the distances only",
    )
    displacement_confirm_chi2: PositiveFloat | None = Field(
        default=8.0,
        description="likelihood test: name a reflector only if the parity test (which "
        "projects the estimate's position error out) gives it at least this too: with wheel "
        "slip the estimate lags by 5-10 cm, which the likelihood test alone takes for a "
        "moved reflector; None: no confirmation",
    )
    displacement_gate_m: PositiveFloat = Field(
        default=0.15,
        description="parity test: residuals within this enter it (farther ones are "
        "another return's; the miss count covers reflectors moved farther)",
    )
    displacement_std_m: PositiveFloat = Field(
        default=0.03,
        description="std of a reflector's measured distance about the one a displacement "
        "predicts (radar range noise; the parity test projects the pose error out)",
    )
    displacement_window_frames: Annotated[int, Field(ge=2, le=100_000)] = Field(
        default=30,
        description="the displacement test forgets over about this many frames: about the "
        "naming budget, and a longer window adds up slow, correlated noise (clutter) too",
    )
    range_std_m: PositiveFloat = Field(
        default=0.035,
        description="std of a reflector's distance from a converged estimate (radar range "
        "noise, about 2.6 cm, and the estimate's error; not the localiser's inflated "
        "measurement_std_m): ghosts and room returns crowd the reflector band, so the gate "
        "must be as tight as the radar allows",
    )
    mask_excess_db: NonNegFloat | None = Field(
        default=None,
        description="if set (10 was measured), a frame does not judge a reflector when a "
        "detection this many dB stronger than the reflector's expected RCS lies within "
        "mask_window_m of its distance (outside the gate): such a return can hide it (CFAR, "
        "peak search), and a masked reflector looks missing or moved. Under strong clutter "
        "it halves the false names of small reflectors but costs some naming of moved or "
        "removed ones (docs/robustness.md); None (default): off",
    )
    mask_window_m: PositiveFloat = Field(
        default=0.3,
        description="how far from a reflector's distance a much stronger return can hide it",
    )
    min_gain: Fraction = Field(
        default=0.25,
        description="share of its peak RCS a reflector must show the radar to count as visible",
    )

    @model_validator(mode="after")
    def _hysteresis(self) -> ReflectorMonitorConfig:
        if not self.clear_share < self.suspect_share:
            raise PydanticCustomError(
                "hysteresis",
                "clear_share ({a}) must be below suspect_share ({b})",
                {"a": self.clear_share, "b": self.suspect_share},
            )
        return self


class ClutterMapConfig(Strict):
    """Unmapped static scatterers learnt while localised (lrp_gym.localization.clutter_map).

    Off by default: on the simulated clutter (docs/robustness.md) it gained nothing
    measurable, and it costs about 6 % of a step.
    """

    enabled: bool = False
    gate_m: PositiveFloat = Field(
        default=0.1,
        description="a distance within this of a clutter point's predicted distance is its "
        "return (the radar's 2.6 cm range noise, the estimate's and the point's errors)",
    )
    explain_gate_m: PositiveFloat = Field(
        default=0.06,
        description="a distance within this of a mapped reflector's or a known point's "
        "predicted distance is no evidence of a new point",
    )
    window_frames: Annotated[int, Field(ge=4, le=1000)] = Field(
        default=40, description="localised frames kept to search for new points"
    )
    min_observations: Annotated[int, Field(ge=4, le=1000)] = Field(
        default=12, description="frames with a return at a point's distance, at least"
    )
    min_spread_m: PositiveFloat = Field(
        default=0.15,
        description="std of the radar positions across their main direction, at least: from "
        "a straight line a point and its mirror image give the same distances",
    )
    max_rms_m: PositiveFloat = Field(
        default=0.04, description="largest RMS distance residual of an accepted point's fit"
    )
    forget_frames: Annotated[int, Field(ge=1, le=100_000)] = Field(
        default=40,
        description="localised frames in range without a return before a point is forgotten",
    )
    max_points: Annotated[int, Field(ge=1, le=10_000)] = 32
    dead_reckoning_frames: Annotated[int, Field(ge=0, le=10_000)] = Field(
        default=20,
        description="frames after the last converged estimate for which the clutter returns "
        "are still taken out, predicted from that estimate and the odometry",
    )


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
        description="with reflector_visibility, in rooms that need it: poses of a calibration "
        "survey (radar frames at random free poses, fixed seed) that measures how often the "
        "radar delivers each reflector in view; a reflector delivered less often than "
        "detection_probability gets its measured rate instead (never more: misses repeat "
        "along the path); 0: no survey",
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
        description="while the estimate is converged, the lost test quiet, no recovery under "
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
        description="inflate the motion noise while the converged estimate keeps moving away "
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
