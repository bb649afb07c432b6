"""Do the surveyed ghost weights explain new radar frames better than equal ones?
(docs/trust.md, session 27)

Held out from the survey (other poses, other noise: seed 99), per room: the log-likelihood of
each frame's RCS-window distances at the true position with the surveyed weights minus with
equal ones, and the margin of the true position over the best position more than 1 m away
(0.1 m grid) under each.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/ghost_weights_heldout.py [--frames 40]
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from lrp_gym.config import load_scenario
from lrp_gym.experiments.scenarios import generated_room
from lrp_gym.localization.factory import measured_mixture, radar_link
from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.radar.delivery_rate import random_poses
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.tracking.tracker import LrpTracker
from lrp_gym.world.world import World

FAST = {"radar": {"fidelity": "detections"}}
SPHERES = {
    **FAST,
    "reflectors": {"types": {"A": {"kind": "sphere", "diameter_m": 0.2}}},
}


def rooms() -> dict:
    return {
        "paper room, four spheres": load_scenario("ipin2023").with_overrides(SPHERES),
        "generated room 7": generated_room(7, FAST),
        "generated room 8": generated_room(8, FAST),
        "2 + 2 paper layout": load_scenario("ipin2023-2types").with_overrides(FAST),
    }


def held_out(cfg, frames: int) -> tuple[np.ndarray, np.ndarray]:
    """Per frame: the gain at the truth, and (surveyed, equal) margins over the best wrong."""
    world = World.from_config(cfg)
    sensor = RadarSensor(world, cfg.radar)
    link = radar_link(cfg, sensor)
    loc = measured_mixture(cfg)
    equal = replace(link, ghost_weights=None)
    models = [FingerprintModel.for_world(world, loc, lk) for lk in (link, equal)]
    classifier = LrpTracker.from_world(world, cfg.tracking).classifier
    rng = np.random.default_rng(99)
    poses, vels = random_poses(world, frames, rng, cfg.robot.radius_m, cfg.robot.max_speed_mps)
    gx, gy = np.meshgrid(*(np.arange(0.2, s, 0.1) for s in world.room.size_m[:2]))
    grid = np.c_[gx.ravel(), gy.ravel()]
    gain, margins = [], []
    for pose, vel in zip(poses, vels, strict=True):
        det = sensor.detect(sensor.paths(pose, vel), rng)
        cand = classifier.candidates(det)
        types = range(cand.shape[1])
        fp = Fingerprint.from_distances(
            world.layout.type_names, [det.range_m[cand[:, t]] for t in types]
        )
        wrong = grid[np.hypot(*(grid - pose[:2]).T) > 1.0]
        truth = [m.log_likelihood(pose[None, :2], fp)[0] for m in models]
        best = [m.log_likelihood(wrong, fp).max() for m in models]
        gain.append(truth[0] - truth[1])
        margins.append(np.subtract(truth, best))
    return np.array(gain), np.array(margins)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=40)
    args = ap.parse_args()
    print(
        "room | gain at the truth (nats), mean; frames > 0 | margin over the best wrong "
        "position, surveyed / equal | frames the truth is best, surveyed / equal"
    )
    for label, cfg in rooms().items():
        gain, margins = held_out(cfg, args.frames)
        s, e = margins.mean(axis=0)
        ws, we = (margins > 0).mean(axis=0)
        print(
            f"{label} | {gain.mean():.2f}; {100 * np.mean(gain > 0):.0f} % | {s:.2f} / {e:.2f} "
            f"| {100 * ws:.0f} % / {100 * we:.0f} %"
        )


if __name__ == "__main__":
    main()
