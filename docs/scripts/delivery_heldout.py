"""Reflectors the link budget sees from everywhere but the radar delivers rarely
(docs/trust.md, session 28).

Per room: each reflector's delivered rate in view from the survey (200 frames, seed 0), and,
on frames held out from it (other poses and noise: seed 99), the log-likelihood of each
frame's RCS-window distances at the true position with the surveyed rates minus with every
reflector expected at ``detection_probability``, and the margin of the true position over
the best position more than 1 m away (0.1 m grid) under each.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/delivery_heldout.py [--rooms 3,7,13] [--frames 40]
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from lrp_gym.experiments.ghost_evidence import held_out_margins
from lrp_gym.experiments.scenarios import generated_room
from lrp_gym.localization.factory import radar_link
from lrp_gym.radar.delivery_rate import lrp_detection_rate
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world.world import World


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rooms", default="3,7,13")
    ap.add_argument("--frames", type=int, default=40)
    args = ap.parse_args()
    print(
        "room | delivered in view (survey) | gain at the truth (nats), mean; frames > 0 | "
        "margin over the best wrong position, surveyed / P_D | frames the truth is best"
    )
    for room in (int(r) for r in args.rooms.split(",")):
        cfg = generated_room(room, {"radar": {"fidelity": "detections"}})
        link = radar_link(cfg, RadarSensor(World.from_config(cfg), cfg.radar))
        rates = lrp_detection_rate(cfg, cfg.localization.detection_survey_poses, seed=0)
        shown = " ".join(f"{r:.2f}" for r in rates.per_lrp_in_view_rate)
        if link.delivery is None:
            print(f"generated room {room} | {shown} | (plain model: nothing to compare)")
            continue
        ev = held_out_margins(cfg, (link, replace(link, delivery=None)), args.frames)
        s, e = ev.margin_nats.mean(axis=0)
        ws, we = (ev.margin_nats > 0).mean(axis=0)
        print(
            f"generated room {room} | {shown} | {ev.gain_nats.mean():.2f}; "
            f"{100 * np.mean(ev.gain_nats > 0):.0f} % | {s:.2f} / {e:.2f} | "
            f"{100 * ws:.0f} % / {100 * we:.0f} %"
        )


if __name__ == "__main__":
    main()
