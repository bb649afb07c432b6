"""Schema of what the localiser learns where the room differs from its map: mapped reflectors
that moved or went missing (the reflector monitor), unmapped static scatterers (the clutter
map)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from lrp_gym.config.base import Fraction, NonNegFloat, PositiveFloat, Probability, Strict


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
        description="frames after the last settled estimate for which the clutter returns "
        "are still taken out, predicted from that estimate and the odometry",
    )
