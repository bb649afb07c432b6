"""What the converged-but-wrong steps look like under clutter (docs/trust.md, session 18).

Pure pursuit on the env's default task with unmapped scatterers (``perturbations.clutter``):
for the converged steps that are right and those off by more than 0.3 m, the 10th, 50th and
90th percentiles of the step index, the distance driven since the reset, the confidence, the
particle count and the whole cloud's position std (``info["pose_std"]``, x and y combined).

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/wrong_converged_features.py --seeds 7300-7399 \
        [--severity 0.5] [--set KEY=VALUE]
"""

from __future__ import annotations

import argparse
from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import numpy as np

import lrp_gym  # noqa: F401  (registers the ids)
from agents.pure_pursuit import PurePursuitPolicy
from lrp_gym.commands._common import parse_sets
from lrp_gym.localization.metrics import CONFIDENTLY_WRONG_M

FEATURES = ("step", "driven_m", "confidence", "particles", "cloud_std_m")


def default_task_steps(
    seeds: range, severity: float, overrides: dict | None = None
) -> Iterator[tuple[int, dict, Any]]:
    """Pure pursuit on the default task under clutter ``severity`` (0: none), with the
    scenario ``overrides`` (e.g. a room with obstacles): for the reset (step 0) and every
    step of every seed, the step's index, its info and the localiser (its particles as they
    are after the step)."""
    over = dict(overrides or {})
    if severity > 0.0:
        over["perturbations"] = {"clutter": {"severity": severity}}
    env = gym.make("LRPRadarNavFast-v0", task_mode="goal", overrides=over)
    policy = PurePursuitPolicy.from_env(env)
    localizer = env.unwrapped.core.stacks[0].localizer
    try:
        for seed in seeds:
            policy.reset()
            obs, info = env.reset(seed=seed)
            step, done = 0, False
            yield step, info, localizer
            while not done:
                obs, _, terminated, truncated, info = env.step(policy.act(obs))
                done, step = terminated or truncated, step + 1
                yield step, info, localizer
    finally:
        env.close()


def study_args(doc: str, sets: tuple[str, ...] = ()) -> argparse.Namespace:
    """The options of the scripts built on :func:`default_task_steps`: ``--seeds FIRST-LAST``
    (``.seeds``, a range), ``--severity`` of the clutter and ``--set KEY=VALUE`` (repeatable,
    after ``sets``; ``.overrides``, the scenario override dict)."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--seeds", default="7300-7399", help="FIRST-LAST")
    ap.add_argument("--severity", type=float, default=0.5, help="clutter severity (0: none)")
    ap.add_argument("--set", action="append", default=[], dest="sets", metavar="KEY=VALUE")
    args = ap.parse_args()
    first, last = (int(s) for s in args.seeds.split("-"))
    args.seeds = range(first, last + 1)
    args.overrides = parse_sets([*sets, *args.sets])
    return args


def converged_steps(
    seeds: range, severity: float, overrides: dict | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Features (K, 5) of every converged step, and whether each is wrong (K,)."""
    rows, wrong = [], []
    for step, info, _ in default_task_steps(seeds, severity, overrides):
        xy = np.asarray(info["true_pose"])[:2]
        if step == 0:  # the reset
            driven, last_xy = 0.0, xy
            continue
        driven, last_xy = driven + float(np.hypot(*(xy - last_xy))), xy
        if info["converged"]:
            std = np.asarray(info["pose_std"])
            cloud = float(np.hypot(std[0], std[1]))
            conf = info["localization_confidence"]
            rows.append((step, driven, conf, info["n_particles"], cloud))
            wrong.append(info["position_error_m"] > CONFIDENTLY_WRONG_M)
    return np.array(rows, float).reshape(-1, len(FEATURES)), np.array(wrong, bool)


def main() -> None:
    args = study_args(__doc__)
    x, wrong = converged_steps(args.seeds, args.severity, args.overrides)
    print(f"{len(wrong)} converged steps, {int(wrong.sum())} wrong (> {CONFIDENTLY_WRONG_M} m)")
    print("feature | right: p10 / p50 / p90 | wrong: p10 / p50 / p90")
    for k, name in enumerate(FEATURES):
        cells = [
            " / ".join(f"{v:.3g}" for v in np.percentile(x[sel, k], [10, 50, 90]))
            if sel.any()
            else "-"
            for sel in (~wrong, wrong)
        ]
        print(f"{name} | {cells[0]} | {cells[1]}")


if __name__ == "__main__":
    main()
