"""How well can a move be told from a pose error? The parity test's noncentrality per episode.

Records EPISODES patrol episodes with one reflector moved by SHIFT metres (as
``monitor_replay.py`` does; seeds FIRST_SEED..) and, on the true poses of the first 40 frames
(the naming budget), accumulates the parity-space test
(:mod:`lrp_gym.localization.displacement_test`, 3 cm range noise, forgetting over 30 frames)
on noise-free residuals: the moved reflector's offset ``u . d``, zero for the others. The
statistic it reaches is the noncentrality (a real run's statistic averages it plus 2, the
chi-square's 2 dof): what the move leaves once any position error is removed frame by frame. A move
whose pattern of distances a shift of the robot's position mimics along the path has a small
noncentrality, and no test that allows for an unknown pose error (wheel slip) can name it
reliably within the budget. Prints ``seed:noncentrality`` per episode and the seeds below 20.

    python docs/scripts/move_observability.py ipin2023-patrol 0.25 50
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from monitor_replay import record  # noqa: E402

from lrp_gym.experiments.robustness import SUSPECT_BUDGET_FRAMES  # noqa: E402
from lrp_gym.localization.displacement_test import DisplacementTest  # noqa: E402
from lrp_gym.localization.reflector_monitor import ReflectorMonitor  # noqa: E402


def noncentrality(ep: dict) -> float:
    """The moved reflector's parity statistic on noise-free residuals after the budget."""
    monitor = ReflectorMonitor(ep["world"], ep["cfg"], ep["max_range_m"])
    j = sorted(ep["moved"])[0]
    shift = ep["offsets_m"][0, :2]
    test = DisplacementTest(len(ep["world"].layout), 0.03, np.inf, 30)
    for pose in ep["true_poses"][:SUSPECT_BUDGET_FRAMES]:
        _, seen, bearing, _ = monitor._geometry(np.asarray(pose[:2], dtype=float))
        residual = np.zeros(len(seen))
        residual[j] = bearing[j] @ shift
        test.add(seen, residual, bearing)
    return float(test.statistic[j])


def main(scenario: str, shift_m: float, episodes: int, first_seed: int = 0) -> None:
    recorded = record(scenario, "displaced_reflector", shift_m, episodes, first_seed)
    lam = [noncentrality(ep) for ep in recorded]
    print(" ".join(f"{first_seed + k}:{v:.0f}" for k, v in enumerate(lam)))
    low = [first_seed + k for k, v in enumerate(lam) if v < 20.0]
    print(f"noncentrality below 20 (hard to tell from a pose error): {low}")


if __name__ == "__main__":
    first = int(sys.argv[4]) if len(sys.argv) > 4 else 0
    main(sys.argv[1], float(sys.argv[2]), int(sys.argv[3]), first)
