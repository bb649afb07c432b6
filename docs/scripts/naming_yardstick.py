"""What an ideal detector could name: a displaced reflector seen from the true poses.

Records EPISODES patrol episodes with one reflector moved by SHIFT metres (as
``monitor_replay.py`` does; seeds 0..EPISODES-1, drop_suspects off) and compares, per episode,
whether the moved reflector is named within 40 frames
- by the monitor on the recorded frames (estimated pose, the detections);
- by an ideal detector: the true pose, every visible reflector's true distance with the
  radar's 2.6 cm range noise and no other return, fed to the same monitor (its miss test and
  its displacement test).

    python docs/scripts/naming_yardstick.py ipin2023-patrol 0.25 50
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from monitor_replay import record, replay  # noqa: E402

from lrp_gym.experiments.robustness import SUSPECT_BUDGET_FRAMES  # noqa: E402
from lrp_gym.localization.monitor_frame import MonitorFrame, nearest_residuals  # noqa: E402
from lrp_gym.localization.reflector_monitor import ReflectorMonitor  # noqa: E402


def ideal_named(ep: dict, rng: np.random.Generator) -> tuple[bool, bool]:
    """(named by the monitor, named by its misses alone) within the naming budget, on the
    ideal detector's frames."""
    world, cfg = ep["world"], ep["cfg"]
    true_pos = world.layout.positions_m.copy()
    moved = sorted(ep["moved"])
    true_pos[moved] += ep["offsets_m"]
    monitors = [
        ReflectorMonitor(world, c, ep["max_range_m"])
        for c in (cfg, cfg.model_copy(update={"displacement_chi2": None}))
    ]
    named = [False, False]
    for pose in ep["true_poses"][:SUSPECT_BUDGET_FRAMES]:
        predicted, seen, bearing, _ = monitors[0]._geometry(pose[:2])
        radar = world.radar_position(np.asarray(pose[:2], float))
        measured = np.linalg.norm(true_pos - radar, axis=1) + rng.normal(0, 0.026, len(seen))
        z = np.sort(measured[seen])  # only the reflectors in view answer
        frame = MonitorFrame(seen, nearest_residuals(predicted, z), bearing, predicted, z)
        for k, mon in enumerate(monitors):
            mon.accumulate(frame)
            named[k] |= bool(set(mon.suspects) & ep["moved"])
    return named[0], named[1]


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
