"""Replay the reflector monitor with other settings on the same recorded frames.

Runs EPISODES patrol episodes of one robustness cell (pure pursuit, detections fidelity,
seeds FIRST_SEED..FIRST_SEED+EPISODES-1, FIRST_SEED 0 unless given, the monitor's
``drop_suspects`` off so that its verdicts do not change the trajectory), records what the
monitor saw on every frame (estimate, gated distances, clutter map points, wheel speed, the
frame's detections), then replays a fresh monitor per variant on those frames. Prints, per
variant, the episodes naming the moved reflector within 40 frames and the episodes naming
another one.

    python docs/scripts/monitor_replay.py ipin2023-patrol displaced_reflector 0.25 20
    python docs/scripts/monitor_replay.py ipin2023-2types-patrol clutter 0.5 20
    python docs/scripts/monitor_replay.py ipin2023-patrol displaced_reflector 0.25 50 100

The settings of session 11 (the Doppler weight, the masking option) were chosen on seeds 100
and up. The 50-episode matrix runs seeds 0-49: until its monitor names a reflector, its
trajectories are those recorded here, so a replay of those seeds gives the matrix's first name.
"""

from __future__ import annotations

import sys
from types import SimpleNamespace

from agents.registry import make_agent
from lrp_gym.config import deep_merge
from lrp_gym.experiments.episodes import make_eval_env
from lrp_gym.experiments.robustness import SUSPECT_BUDGET_FRAMES, cell_overrides
from lrp_gym.localization import reflector_monitor as rm

VARIANTS = {
    "session 8 (misses + bias test)": {"bias_m": 0.04, "displacement_chi2": None},
    "misses only": {"displacement_chi2": None},
    "misses + parity test (session 9)": {
        "displacement_test": "parity",
        "displacement_chi2": 20.0,
        "displacement_lead": 10.0,
        "displacement_window_frames": 50,
    },
    "misses + likelihood test, unconfirmed": {"displacement_confirm_chi2": None},
    "misses + likelihood test, distances only (session 10)": {"displacement_doppler_std_mps": 0.0},
    "misses + likelihood test (default)": {},
    "misses + likelihood test, masking at 10 dB": {"mask_excess_db": 10.0},
}


def record(
    scenario: str, perturbation: str, severity: float, episodes: int, first_seed: int = 0
) -> list[dict]:
    over = cell_overrides(perturbation, severity) if perturbation != "none" else {}
    over = deep_merge(over or {}, {"localization": {"reflector_monitor": {"drop_suspects": False}}})
    env = make_eval_env("pure-pursuit", "LRPRadarNavFast-v0", scenario, overrides=over)
    policy = make_agent("pure-pursuit", env)
    base = env.unwrapped
    frames: list = []
    update = rm.ReflectorMonitor.update

    def recording(self, estimate, gated, others_m=None, speed_mps=None, detections=None):
        frames.append((estimate, gated, others_m, speed_mps, detections))
        return update(self, estimate, gated, others_m, speed_mps, detections)

    rm.ReflectorMonitor.update = recording
    out = []
    try:
        for seed in range(first_seed, first_seed + episodes):
            policy.reset()
            obs, _ = env.reset(seed=seed)
            frames.clear()
            poses = []
            for _ in range(base.cfg.task.max_episode_steps):
                obs, _, terminated, truncated, _ = env.step(policy.act(obs))
                poses.append(base.pose.copy())
                if terminated or truncated:
                    break
            moved = base.perturbations.get("displaced_reflector") if base.perturbations else None
            out.append(
                {
                    "frames": list(frames),
                    "true_poses": poses,
                    "moved": set() if moved is None else set(moved.moved.tolist()),
                    "offsets_m": None if moved is None else moved.offsets_m.copy(),
                }
            )
    finally:
        rm.ReflectorMonitor.update = update
    monitor = base.stack.monitor
    return [
        dict(e, world=base.world, cfg=monitor.cfg, max_range_m=monitor.max_range_m) for e in out
    ]


def replay(episode: dict, changes: dict) -> dict[int, int]:
    """First frame at which each reflector is named by a monitor with ``changes``."""
    mon = rm.ReflectorMonitor(
        episode["world"], episode["cfg"].model_copy(update=changes), episode["max_range_m"]
    )
    named: dict[int, int] = {}
    for k, (estimate, gated, others, speed, detections) in enumerate(episode["frames"], start=1):
        # A copy of the estimate: the recorded object is the stack's own.
        est = SimpleNamespace(converged=estimate.converged, pose=estimate.pose)
        mon.update(est, gated, others, speed, detections)
        for j in mon.suspects:
            named.setdefault(j, k)
    return named


def main(
    scenario: str, perturbation: str, severity: float, episodes: int, first_seed: int = 0
) -> None:
    recorded = record(scenario, perturbation, severity, episodes, first_seed)
    print(f"{scenario}, {perturbation} {severity:g}, {episodes} episodes")
    for name, changes in VARIANTS.items():
        right = wrong = 0
        for ep in recorded:
            named = replay(ep, changes)
            right += any(k <= SUSPECT_BUDGET_FRAMES for j, k in named.items() if j in ep["moved"])
            wrong += bool(set(named) - ep["moved"])
        print(f"  {name:38s} moved one named {right:3d}   another named {wrong:3d}")


if __name__ == "__main__":
    first = int(sys.argv[5]) if len(sys.argv) > 5 else 0
    main(sys.argv[1], sys.argv[2], float(sys.argv[3]), int(sys.argv[4]), first)
