"""What the likelihood's detection model costs in the obstacle room: building the table
once per world, and one frame's lookup for 10 000 particles against the exact computation.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/visibility_cost.py
"""

from __future__ import annotations

import time

import numpy as np

from lrp_gym.config import load_scenario
from lrp_gym.localization.visibility import RadarLink, ReflectorVisibility
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world.world import World

BOX = {"min": [0.8, 1.4, 0.0], "max": [2.2, 2.6, 1.0]}
REPEATS = 20


def _ms_per_call(fn, xy: np.ndarray) -> float:
    t0 = time.perf_counter()
    for _ in range(REPEATS):
        fn(xy)
    return 1e3 * (time.perf_counter() - t0) / REPEATS


def main() -> None:
    cfg = load_scenario("ipin2023").with_overrides({"room": {"obstacles": [BOX]}})
    world = World.from_config(cfg)
    link = RadarLink.from_sensor(RadarSensor(world, cfg.radar))
    t0 = time.perf_counter()
    table = ReflectorVisibility.for_world(world, link)
    print(f"table of {table.table.shape[1]} nodes built in {time.perf_counter() - t0:.3f} s")
    xy = np.random.default_rng(0).uniform(0.0, 5.0, (10_000, 2))
    print(f"10 000 positions: table {_ms_per_call(table.detection_probability, xy):.2f} ms, "
          f"exact {_ms_per_call(table.exact.detection_probability, xy):.2f} ms")  # fmt: skip


if __name__ == "__main__":
    main()
