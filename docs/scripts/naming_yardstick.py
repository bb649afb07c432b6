"""What an ideal detector could name: a displaced reflector seen from the true poses.

Records EPISODES patrol episodes with one reflector moved by SHIFT metres (as
``monitor_replay.py`` does; seeds 0..EPISODES-1, drop_suspects off) and compares, per episode,
whether the moved reflector is named within 40 frames
- by the monitor on the recorded frames (estimated pose, the detections' nearest return);
- by an ideal detector: the true pose, every visible reflector's true distance with the
  radar's 2.6 cm range noise and no other return, the monitor's miss test (share >= 0.25 of
  >= 12 visible frames outside the 0.105 m gate) and its displacement test.

    python docs/scripts/naming_yardstick.py ipin2023-patrol 0.25 50
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from monitor_replay import record, replay  # noqa: E402

from lrp_gym.experiments.robustness import SUSPECT_BUDGET_FRAMES  # noqa: E402
from lrp_gym.localization.displacement_test import DisplacementTest  # noqa: E402
from lrp_gym.localization.reflector_monitor import ReflectorMonitor  # noqa: E402


def ideal_named(ep: dict, rng: np.random.Generator) -> tuple[bool, bool]:
    """(named by either test, named by misses alone) within the naming budget."""
    world, cfg = ep["world"], ep["cfg"]
    mon = ReflectorMonitor(world, cfg, ep["max_range_m"])
    layout = world.layout.positions_m
    true_pos = layout.copy()
    moved = sorted(ep["moved"])
    true_pos[moved] += ep["offsets_m"]
    test = DisplacementTest(
        len(layout), cfg.displacement_std_m, cfg.displacement_gate_m, cfg.displacement_window_frames
    )
    seen_n, misses = np.zeros(len(layout)), np.zeros(len(layout))
    gate_m = cfg.gate_sigmas * cfg.range_std_m
    by_test = by_misses = False
    for pose in ep["true_poses"][:SUSPECT_BUDGET_FRAMES]:
        pred, seen, bearing = mon._geometry(pose[:2])
        radar = world.radar_position(np.asarray(pose[:2], float))
        residual = np.linalg.norm(true_pos - radar, axis=1) + rng.normal(0, 0.026, len(pred)) - pred
        test.add(seen, residual, bearing)
        seen_n += seen
        misses += seen & (np.abs(residual) > gate_m)
        by_test |= test.leader(cfg.displacement_chi2, cfg.displacement_lead) in moved
        share = np.divide(misses, seen_n, out=np.zeros_like(misses), where=seen_n > 0)
        by_misses |= bool(
            np.any(((seen_n >= cfg.min_visible_frames) & (share >= cfg.suspect_share))[moved])
        )
    return by_test or by_misses, by_misses


def main(scenario: str, shift_m: float, episodes: int) -> None:
    recorded = record(scenario, "displaced_reflector", shift_m, episodes)
    rng = np.random.default_rng(0)
    ideal = ideal_misses = monitor = 0
    for ep in recorded:
        both, misses = ideal_named(ep, rng)
        ideal += both
        ideal_misses += misses
        named = replay(ep, {})
        monitor += any(k <= SUSPECT_BUDGET_FRAMES for j, k in named.items() if j in ep["moved"])
    n = len(recorded)
    print(
        f"{scenario}, displaced {shift_m:g} m, {n} episodes, named within "
        f"{SUSPECT_BUDGET_FRAMES} frames: ideal detector {ideal} ({ideal_misses} by misses "
        f"alone); the monitor on the recorded frames {monitor}"
    )


if __name__ == "__main__":
    main(sys.argv[1], float(sys.argv[2]), int(sys.argv[3]))
