"""Does a surveyed part of the measurement model explain new radar frames better?

Held out from the surveys (other poses, other noise), each frame's RCS-window distances are
weighed by the localisers' likelihood twice, with two radar links: the surveyed ghost weights
against equal ones (:func:`held_out_evidence`, docs/trust.md session 27), or any pair
(:func:`held_out_margins`; the surveyed delivery rates against none, session 28). A better
model makes the frames more likely at the true position and sets the true position further
above wrong ones.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from lrp_gym.config import ScenarioConfig
from lrp_gym.localization.factory import measured_mixture, radar_link
from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.localization.visibility import RadarLink
from lrp_gym.radar.delivery_rate import random_poses
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.tracking.tracker import LrpTracker
from lrp_gym.world.world import World

#: Positions at least this far from the truth count as wrong (m).
WRONG_M = 1.0
#: Spacing of the floor grid searched for the best wrong position (m).
GRID_M = 0.1


@dataclass(frozen=True)
class GhostEvidence:
    """Per held-out frame (F,).

    Attributes
    ----------
    gain_nats : ndarray (F,)
        Log-likelihood at the true position, the first link's model minus the second's
        (surveyed ghost weights minus equal ones in :func:`held_out_evidence`).
    margin_nats : ndarray (F, 2)
        The true position's log-likelihood minus the best wrong position's, under the first
        link's model (column 0) and the second's (column 1).
    """

    gain_nats: np.ndarray
    margin_nats: np.ndarray


def held_out_evidence(cfg: ScenarioConfig, frames: int = 40, seed: int = 99) -> GhostEvidence:
    """:class:`GhostEvidence` of scenario ``cfg`` over ``frames`` radar frames at random free
    poses (``seed``: the poses and the noise; the survey's is 0). ``cfg`` needs surveyed
    weights (a radar link with ``ghost_weights``)."""
    link = radar_link(cfg, RadarSensor(World.from_config(cfg), cfg.radar))
    if link.ghost_weights is None:
        raise ValueError(f"{cfg.name}: no surveyed ghost weights (localization.ghost_weights)")
    return held_out_margins(cfg, (link, replace(link, ghost_weights=None)), frames, seed)


def held_out_margins(
    cfg: ScenarioConfig, links: tuple[RadarLink, RadarLink], frames: int = 40, seed: int = 99
) -> GhostEvidence:
    """:class:`GhostEvidence` of two localiser models of ``cfg`` that differ only in their
    radar ``links`` (the gain is the first's log-likelihood at the truth minus the second's;
    the margins are per model, in that order), over ``frames`` held-out frames at random
    free poses (``seed``)."""
    world = World.from_config(cfg)
    sensor = RadarSensor(world, cfg.radar)
    loc = measured_mixture(cfg)
    models = [FingerprintModel.for_world(world, loc, lk) for lk in links]
    classifier = LrpTracker.from_world(world, cfg.tracking).classifier
    rng = np.random.default_rng(seed)
    poses, vels = random_poses(world, frames, rng, cfg.robot.radius_m, cfg.robot.max_speed_mps)
    gx, gy = np.meshgrid(*(np.arange(2 * GRID_M, s, GRID_M) for s in world.room.size_m[:2]))
    grid = np.c_[gx.ravel(), gy.ravel()]
    gain, margins = [], []
    for pose, vel in zip(poses, vels, strict=True):
        det = sensor.detect(sensor.paths(pose, vel), rng)
        cand = classifier.candidates(det)
        per_type = [det.range_m[cand[:, t]] for t in range(cand.shape[1])]
        fp = Fingerprint.from_distances(world.layout.type_names, per_type)
        wrong = grid[np.hypot(*(grid - pose[:2]).T) > WRONG_M]
        truth = [m.log_likelihood(pose[None, :2], fp)[0] for m in models]
        best = [m.log_likelihood(wrong, fp).max() for m in models]
        gain.append(truth[0] - truth[1])
        margins.append(np.subtract(truth, best))
    return GhostEvidence(np.array(gain), np.array(margins))
