"""One radar frame through identification and positioning, in the order the data allow.

AMCL can weigh every gated detection (``measurements: detections``) or the tracked fingerprint
(``tracks``). In the first case it does not need the tracker, so it runs first and its
posterior cloud identifies the reflectors for the tracker in the same frame; in the second the
tracker runs first, identified by AMCL's cloud of the previous frame moved by the odometry. The env,
``reproduce-paper`` and ``lrp-gym track`` all go through :func:`track_and_localize`.
"""

from __future__ import annotations

import numpy as np

from lrp_gym.localization.estimate import PoseEstimate
from lrp_gym.localization.factory import Localizer
from lrp_gym.radar.detections import Detections
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.tracking.motion import EgoMotion
from lrp_gym.tracking.prior import DistancePrior
from lrp_gym.tracking.tracker import LrpTracker
from lrp_gym.world.robot import apply_odometry
from lrp_gym.world.world import World


def track_and_localize(
    world: World,
    tracker: LrpTracker,
    amcl: Localizer,
    detections: Detections,
    dt_s: float,
    ego: EgoMotion,
    last_estimate: PoseEstimate | None,
    rng: np.random.Generator,
    *,
    measurements: str = "detections",
    map_aided: bool = True,
    use_ego: bool = True,
) -> tuple[Fingerprint, PoseEstimate]:
    """Update the tracker and AMCL with one frame.

    Parameters
    ----------
    world : World
    tracker : LrpTracker
    amcl : Amcl or GridFilter
        The localiser (AMCL's interface; "AMCL" below).
    detections : Detections
        This frame's radar output.
    dt_s : float
        Time since the previous frame.
    ego : EgoMotion
        Speed now and odometry since the previous frame (AMCL's motion input too).
    last_estimate : PoseEstimate or None
        AMCL's estimate of the previous frame: with ``tracks``, whether it had converged
        decides whether the prior may rank the tracks or only veto them.
    rng : numpy.random.Generator
        AMCL's randomness; the tracker draws none.
    measurements : {"detections", "tracks"}
        What AMCL weighs.
    map_aided : bool
        Identify the reflectors with AMCL's prediction (else RCS, motion and track quality
        only, as in the paper).
    use_ego : bool
        Give the tracker the odometry (static-point prediction, Doppler bound); else the
        paper's constant-velocity model.

    Returns
    -------
    fingerprint : Fingerprint
        The tracker's estimated fingerprint.
    estimate : PoseEstimate
        AMCL's estimate after this frame.
    """
    odometry = ego.odometry
    tracker_ego = ego if use_ego else None
    # Augmented MCL's fit statistic: on what AMCL weighs, or on the persistent tracks, scored
    # on the same predicted cloud once the tracker has run.
    own_fit = amcl.cfg.recovery_measurements == "detections"
    if measurements == "detections":
        gated = tracker.gated_fingerprint(detections)
        estimate = amcl.update(
            odometry, gated if gated.count else None, rng, recovery=own_fit, speed_mps=ego.speed_mps
        )
        prior = None
        if map_aided:
            # The posterior cloud of this frame, thinned; it ranks the tracks only once
            # converged (right after a global start its heaviest mode may be a mirror image).
            prior = DistancePrior.from_particles(
                world.layout,
                world.mount_height_m,
                amcl.particles[:, :2],
                amcl.weights,
                confident=estimate.converged,
            )
        fingerprint = tracker.update(detections, dt_s, tracker_ego, prior)
    else:
        prior = None
        if map_aided:
            # The cloud before this frame's update, moved by the odometry: AMCL has not seen
            # this frame, so the tracker's output is not fed its own detections back.
            moved = apply_odometry(amcl.particles, odometry)
            prior = DistancePrior.from_particles(
                world.layout,
                world.mount_height_m,
                moved[:, :2],
                amcl.weights,
                confident=last_estimate is not None and last_estimate.converged,
            )
        fingerprint = tracker.update(detections, dt_s, tracker_ego, prior)
        estimate = amcl.update(
            odometry, fingerprint if fingerprint.count else None, rng, recovery=own_fit
        )
    if not own_fit:
        # Tracks updated in this frame only: a coasting track follows the odometry, as a
        # lost filter's cloud does, and would keep its fit up after a kidnap.
        amcl.update_recovery(tracker.persistent_fingerprint(max_misses=0))
    return fingerprint, estimate
