"""How often the radar delivers each reflector in view, per generated room (docs/trust.md,
session 28): the delivery survey's rates (200 frames at random free poses, seed 0, the
detections fidelity) against the likelihood's ``detection_probability``. Reflectors below
the line get the surveyed rate in the likelihood; rooms marked * got it only since session
28 (their link budget detects every reflector from everywhere).

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/delivery_rates_figure.py [--rooms 20] \
        [--out docs/delivery_rates.png]
"""

from __future__ import annotations

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from lrp_gym.experiments.scenarios import generated_room  # noqa: E402
from lrp_gym.localization.visibility import RadarLink, ReflectorVisibility  # noqa: E402
from lrp_gym.radar.delivery_rate import lrp_detection_rate  # noqa: E402
from lrp_gym.radar.sensor import RadarSensor  # noqa: E402
from lrp_gym.world.world import World  # noqa: E402

MARKERS = {"trihedral": "^", "sphere": "o", "luneburg": "s", "van_atta": "D", "point": "x"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rooms", type=int, default=20)
    ap.add_argument("--out", default="docs/delivery_rates.png")
    args = ap.parse_args()
    fig, ax = plt.subplots(figsize=(11, 4.2))
    p_d, labels = None, []
    for room in range(args.rooms):
        cfg = generated_room(room, {"radar": {"fidelity": "detections"}})
        p_d = cfg.localization.detection_probability
        world = World.from_config(cfg)
        rates = np.asarray(lrp_detection_rate(cfg, 200, seed=0).per_lrp_in_view_rate, float)
        needed = ReflectorVisibility.of(world, RadarLink.from_sensor(RadarSensor(world, cfg.radar)))
        new = not needed.needed() and np.nanmin(rates) < p_d
        labels.append(f"{room}*" if new else str(room))
        kinds = [cfg.reflectors.types[r.type].kind for r in cfg.reflectors.layout]
        for j, (rate, kind) in enumerate(zip(rates, kinds, strict=True)):
            x = room + (j - (len(rates) - 1) / 2) * 0.08
            ax.scatter(x, rate, marker=MARKERS.get(kind, "."), color="C3" if rate < p_d else "C0")
    ax.axhline(p_d, color="k", lw=1, ls="--", label=f"detection_probability {p_d}")
    for kind, marker in MARKERS.items():
        ax.scatter([], [], marker=marker, color="grey", label=kind)
    ax.set_xticks(range(args.rooms), labels)
    ax.set_xlabel("generated room (* : surveyed rates only since session 28)")
    ax.set_ylabel("delivered in view (survey)")
    ax.set_ylim(-0.03, 1.03)
    ax.set_title("How often the radar delivers each reflector it can see (red: below P_D)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
