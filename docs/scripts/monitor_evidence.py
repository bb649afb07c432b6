"""What the reflector monitor's returns look like: radial velocities, and strong neighbours.

Records EPISODES patrol episodes of one robustness cell (as ``monitor_replay.py`` does; seeds
FIRST_SEED.., the monitor's verdicts not fed back, ENV_ID ``LRPRadarNavFast-v0`` unless given)
and prints two things, on the converged frames, for the reflectors nothing moved:

- ``velocities``: the radial velocity of a reflector's own return (the return within 5 cm of
  its predicted distance) and of the other returns 0.06-0.4 m from it, minus the velocity that
  the estimated pose and the wheel speed predict for the reflector (``-v . u``);
- ``neighbours``: the miss rate of each reflector type in frames with and without a detection
  10 dB stronger than the reflector's expected RCS 0.1-0.3 m from its distance (what the
  masking option ``mask_excess_db`` acts on).

    python docs/scripts/monitor_evidence.py ipin2023-patrol displaced_reflector 0.25 30
    python docs/scripts/monitor_evidence.py ipin2023-2types-patrol clutter 0.5 30 100
    python docs/scripts/monitor_evidence.py ipin2023-patrol none 0 3 0 LRPRadarNav-v0
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import monitor_replay  # noqa: E402

from lrp_gym.localization.reflector_monitor import ReflectorMonitor  # noqa: E402


def _frames(ep: dict):
    """(monitor frame, detections, radar position) of each judged frame of one episode."""
    monitor = ReflectorMonitor(ep["world"], ep["cfg"], ep["max_range_m"])
    for estimate, gated, others, speed, detections in ep["frames"]:
        frame = monitor.observe(estimate, gated, others, speed)
        if frame is not None:
            radar = ep["world"].radar_position(np.asarray(estimate.pose[:2], dtype=float))
            yield frame, detections, radar


def velocities(recorded: list[dict]) -> None:
    own, other = [], []
    for ep in recorded:
        for f, _, _ in _frames(ep):
            if f.velocities_mps is None:
                continue
            expected = f.expected_velocity_mps
            for j in np.flatnonzero(f.judged):
                if j in ep["moved"]:
                    continue
                gap = np.abs(f.distances_m - f.predicted_m[j])
                dv = f.velocities_mps - expected[j]
                if gap.min() < 0.05:
                    own.append(dv[np.argmin(gap)])
                other.extend(dv[(gap > 0.06) & (gap < 0.4)])
    own, other = np.abs(np.array(own)), np.abs(np.array(other))
    mad = 1.4826 * np.median(np.abs(own - np.median(own)))
    print(
        f"own returns ({len(own)}): 1.48 MAD {mad:.3f} m/s, {np.mean(own > 0.45):.1%} more than "
        f"0.45 m/s off; others ({len(other)}): median {np.median(other):.2f} m/s off, "
        f"{np.mean(other < 0.15):.0%} within 0.15, {np.mean(other < 0.45):.0%} within 0.45"
    )


def neighbours(recorded: list[dict], excess_db: float = 10.0, window_m: float = 0.3) -> None:
    counts: dict[tuple[int, bool], list[int]] = {}
    for ep in recorded:
        cfg, layout = ep["cfg"], ep["world"].layout
        gate = cfg.gate_sigmas * cfg.range_std_m
        for f, det, radar in _frames(ep):
            expected_db = 10.0 * np.log10(np.maximum(layout.effective_rcs_m2(radar), 1e-12))
            for j in np.flatnonzero(f.judged):
                if j in ep["moved"]:
                    continue
                gap = np.abs(det.range_m - f.predicted_m[j])
                strong = (
                    (gap > gate) & (gap <= window_m) & (det.rcs_dbsm >= expected_db[j] + excess_db)
                )
                c = counts.setdefault((int(layout.type_index[j]), bool(strong.any())), [0, 0])
                c[0] += abs(f.residual_m[j]) > gate
                c[1] += 1
    for (t, strong), (miss, n) in sorted(counts.items()):
        print(f"type {t}, {'a' if strong else 'no'} strong neighbour: miss {miss / n:.1%} of {n}")


def main(argv: list[str]) -> None:
    scenario, perturbation, severity, episodes = argv[:4]
    first = int(argv[4]) if len(argv) > 4 else 0
    env_id = argv[5] if len(argv) > 5 else "LRPRadarNavFast-v0"
    make_env = monitor_replay.make_eval_env
    monitor_replay.make_eval_env = lambda agent, _env, scen, overrides=None: make_env(
        agent, env_id, scen, overrides=overrides
    )
    recorded = monitor_replay.record(scenario, perturbation, float(severity), int(episodes), first)
    print(f"{scenario}, {perturbation} {severity}, {episodes} episodes from seed {first}, {env_id}")
    velocities(recorded)
    neighbours(recorded)


if __name__ == "__main__":
    main(sys.argv[1:])
