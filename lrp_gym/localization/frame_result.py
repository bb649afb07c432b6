"""What one frame of the localisation stack produced (:class:`FrameResult`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from lrp_gym.localization.pose_estimate import PoseEstimate
from lrp_gym.radar.detections import Detections
from lrp_gym.tracking.fingerprint import Fingerprint


@dataclass(frozen=True)
class FrameResult:
    """What one frame of the stack produced.

    Attributes
    ----------
    detections : Detections or None
        The radar's detections (after any ``filter_detections`` hook); None when the frame was
        a fingerprint (radar and tracker bypassed, :meth:`LocalizationStack.localize`).
    fingerprint : Fingerprint
        The tracker's fingerprint (or the given one).
    localizer_estimate : PoseEstimate
        The localiser's (AMCL's or the grid filter's) estimate after this frame.
    lut_estimate : PoseEstimate or None
        The look-up table's answer to ``fingerprint`` (position only), if the stack has one.
    estimate : PoseEstimate
        The pose a consumer should use: the localiser's, or with a look-up table its position
        with the localiser's heading.
    elapsed_s : dict
        Wall time of the stages run in this frame: ``radar``, ``tracking_localization``, ``lut``.
    suspect_reflectors : tuple of int
        Layout indices of the reflectors the reflector monitor suspects of being moved or
        missing (:mod:`~lrp_gym.localization.reflector_monitor`); empty without a monitor.
    """

    detections: Detections | None
    fingerprint: Fingerprint
    localizer_estimate: PoseEstimate
    lut_estimate: PoseEstimate | None
    estimate: PoseEstimate
    elapsed_s: dict[str, float] = field(default_factory=dict, compare=False)
    suspect_reflectors: tuple[int, ...] = ()
