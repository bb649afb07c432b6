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

import numpy as np

from lrp_gym.config import load_scenario
from lrp_gym.experiments.ghost_evidence import held_out_evidence
from lrp_gym.experiments.scenarios import generated_room

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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=40)
    args = ap.parse_args()
    print(
        "room | gain at the truth (nats), mean; frames > 0 | margin over the best wrong "
        "position, surveyed / equal | frames the truth is best, surveyed / equal"
    )
    for label, cfg in rooms().items():
        ev = held_out_evidence(cfg, args.frames)
        gain, margins = ev.gain_nats, ev.margin_nats
        s, e = margins.mean(axis=0)
        ws, we = (margins > 0).mean(axis=0)
        print(
            f"{label} | {gain.mean():.2f}; {100 * np.mean(gain > 0):.0f} % | {s:.2f} / {e:.2f} "
            f"| {100 * ws:.0f} % / {100 * we:.0f} %"
        )


if __name__ == "__main__":
    main()
