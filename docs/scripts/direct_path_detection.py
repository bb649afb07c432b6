"""How often the radar detects a reflector's direct path, by its SNR, in one scenario.

At random free poses of a scenario (a shipped one by name, or a generated room by its seed),
for every reflector with a direct path: whether some detection lies within 0.1 m of the path's
range, per 5 dB band of the path's SNR (its power over one cell's noise, before the FFT's
gain), and the share of chance matches (a detection within 0.1 m of the range plus 0.37 m);
then the link budget's mean detection probability of the reflectors in view (what the
localiser's model expects) and ``lrp-gym radar-rate``'s delivered rate in view, per LRP.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/direct_path_detection.py 18   # room seed 18
    PYTHONPATH=$PWD .venv/bin/python docs/scripts/direct_path_detection.py ipin2023
"""

from __future__ import annotations

import argparse

import numpy as np

from lrp_gym.config import load_scenario
from lrp_gym.experiments.scenarios import random_scenario
from lrp_gym.localization.visibility import RadarLink, ReflectorVisibility
from lrp_gym.radar.delivery_rate import lrp_detection_rate, random_poses
from lrp_gym.radar.paths import KIND_NAMES
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world.world import World

TOLERANCE_M = 0.1


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", help="a shipped scenario's name or a generated room's seed")
    ap.add_argument("--poses", type=int, default=300)
    ap.add_argument("--fidelity", default="detections", choices=["detections", "signal"])
    args = ap.parse_args()
    name = args.scenario
    rng = np.random.default_rng(0)
    cfg = (
        random_scenario(np.random.default_rng(int(name))) if name.isdigit() else load_scenario(name)
    )
    world = World.from_config(cfg)
    sensor = RadarSensor(world, cfg.radar.model_copy(update={"fidelity": args.fidelity}))
    poses, vels = random_poses(world, args.poses, rng, cfg.robot.radius_m, cfg.robot.max_speed_mps)
    direct = KIND_NAMES.index("direct")
    rows = []
    for pose, vel in zip(poses, vels, strict=True):
        ranges = np.asarray(sensor.measure(pose, vel, rng).range_m)
        paths = sensor.last_paths
        for j in range(len(world.layout)):
            sel = (paths.reflector_index == j) & (paths.kind == direct)
            if not sel.any():
                continue
            snr_db = 10.0 * np.log10(paths.power_w[sel].max() / sensor.noise_cell)
            d = paths.range_m[sel][0]
            hit = np.any(np.abs(ranges - d) < TOLERANCE_M)
            chance = np.any(np.abs(ranges - d - 0.37) < TOLERANCE_M)
            rows.append((snr_db, hit, chance))
    a = np.array(rows, float)
    print(f"{len(a)} direct paths: detected {a[:, 1].mean():.3f}, chance {a[:, 2].mean():.3f}")
    # What the localiser's model expects there: the link budget's probability, in view.
    vis = ReflectorVisibility.of(world, RadarLink.from_sensor(sensor))
    p = vis.detection_probability(poses[:, :2])
    print(f"the link's detection probability of the reflectors in view: {p[p > 0].mean():.2f}")
    rate = lrp_detection_rate(cfg, args.poses, 0, fidelity=args.fidelity)
    per_lrp = ", ".join(f"{100 * r:.0f}" for r in rate.per_lrp_in_view_rate)
    print(f"delivered in view (radar-rate): {100 * rate.in_view_rate:.1f} %; per LRP {per_lrp} %")
    for lo in np.arange(5 * np.floor(a[:, 0].min() / 5), a[:, 0].max(), 5.0):
        sel = (a[:, 0] >= lo) & (a[:, 0] < lo + 5)
        if sel.any():
            print(f"SNR {lo:5.0f} .. {lo + 5:3.0f} dB: {int(sel.sum()):4d} paths, "
                  f"detected {a[sel, 1].mean():.2f}")  # fmt: skip


if __name__ == "__main__":
    main()
