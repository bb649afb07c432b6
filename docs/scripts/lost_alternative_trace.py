"""One default-task episode under clutter, with and without the lost test's alternative.

Runs the same seed twice (``localization.lost_alternative_drift_nats`` None, then the
default) and draws, frame by frame, the position error and whether the estimate is converged,
and the lost test's two statistics: the best grid cell against the cloud (CUSUM less
``max(4, 0.4 x distances)`` nats per frame) and the grid filter against the cloud (less 1
nat per frame), with the threshold at which recovery particles are injected.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/lost_alternative_trace.py --seed 7063 \
        --out docs/lost_alternative_trace.png
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import lrp_gym  # noqa: E402, F401  (registers the ids)
from agents.pure_pursuit import PurePursuitPolicy  # noqa: E402


def trace(seed: int, severity: float, drift: float | None, frames: int) -> dict[str, np.ndarray]:
    """Per-frame error, converged flag and the lost test's statistics of one episode."""
    over = {
        "perturbations": {"clutter": {"severity": severity}},
        "localization": {"lost_alternative_drift_nats": drift},
    }
    env = gym.make("LRPRadarNavFast-v0", task_mode="goal", overrides=over)
    base = env.unwrapped
    policy = PurePursuitPolicy.from_env(env)
    obs, _ = env.reset(seed=seed)
    rows = []
    for _ in range(frames):
        obs, _, terminated, truncated, info = env.step(policy.act(obs))
        lost = base.localizer.lost
        rows.append(
            (
                info["position_error_m"],
                info["converged"],
                lost.statistic_nats,
                lost.alternative_nats,
                info["localization_confidence"],
            )
        )
        if terminated or truncated:
            break
    env.close()
    a = np.array(rows, dtype=float)
    keys = ("error_m", "converged", "first_nats", "alternative_nats", "confidence")
    return dict(zip(keys, a.T, strict=True))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=7063)
    ap.add_argument("--severity", type=float, default=0.5)
    ap.add_argument("--frames", type=int, default=80)
    ap.add_argument("--out", default="docs/lost_alternative_trace.png")
    args = ap.parse_args()
    without = trace(args.seed, args.severity, None, args.frames)
    with_alt = trace(args.seed, args.severity, 1.0, args.frames)
    fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for run, label, colour in (
        (without, "first statistic only", "C3"),
        (with_alt, "with the alternative", "C0"),
    ):
        t = np.arange(len(run["error_m"]))
        ax0.plot(t, run["error_m"], color=colour, label=label)
        conv = run["converged"] > 0
        ax0.plot(t[conv], run["error_m"][conv], ".", color=colour, ms=5)
    ax0.axhline(0.3, color="grey", lw=0.8, ls=":")
    ax0.set_ylabel("position error (m)\n(dots: converged)")
    ax0.legend(loc="center right")
    ax0.set_title(f"default task, clutter {args.severity}, seed {args.seed}")
    t = np.arange(len(without["first_nats"]))
    ax1.plot(t, without["first_nats"], color="C3", label="best cell vs cloud (first only)")
    t = np.arange(len(with_alt["first_nats"]))
    ax1.plot(t, with_alt["first_nats"], color="C0", ls="--", label="best cell vs cloud")
    ax1.plot(t, with_alt["alternative_nats"], color="C0", label="grid filter vs cloud")
    ax1.axhline(8.0, color="grey", lw=0.8, ls=":", label="threshold (8 nats)")
    ax1.set_ylabel("lost test statistic (nats)")
    ax1.set_xlabel("frame")
    ax1.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
