"""Confidently wrong under clutter, episode by episode (session 13).

Pure pursuit on the env's default task (unknown start pose and heading, sampled goal,
detections fidelity) with unmapped static scatterers (``perturbations.clutter``). Prints one
line per episode (steps, converged steps, converged steps off by > 0.3 m, the longest run of
them, how it ended) and a summary: the share of converged steps that are wrong, and the
episodes stuck (10 or more such steps in a row), as ``lrp-gym robustness`` counts them, and
how far the confidence can be believed: the wrong share (> 0.3 m) of the steps in each band of
``info["localization_confidence"]``, finer near 1 than ``lrp-gym evaluate``'s reliability bins.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/default_task_clutter.py --seeds 7100-7299 \
        [--severity 0.5] [--env LRPRadarNav-v0] [--set localization.lost_alternative_drift_nats=null] \
        [--agent-option arrived_m=0]
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import lrp_gym  # noqa: F401  (registers the ids)
from agents.pure_pursuit import PurePursuitPolicy, parse_options
from lrp_gym.commands._common import overrides
from lrp_gym.localization.metrics import reliability

WRONG_M = 0.3
STUCK_FRAMES = 10
#: Confidence bands of the reliability table: ``settled`` starts at 0.9, ``converged`` at 0.99.
BANDS = (0.0, 0.5, 0.8, 0.9, 0.95, 0.99, 1.0)


def reliability_table(confidence: np.ndarray, errors_m: np.ndarray) -> str:
    """Per confidence band (:data:`BANDS`, the bins of :func:`reliability`): steps, their mean
    confidence and the share off by more than :data:`WRONG_M`."""
    lines = ["confidence band | steps | mean confidence | wrong (> 0.3 m)"]
    for row in reliability(confidence, errors_m, bins=BANDS, wrong_m=WRONG_M):
        band = f"{row['lo']:.2f}-{row['hi']:.2f}"
        if row["steps"]:
            lines.append(
                f"{band} | {row['steps']} | {row['mean_confidence']:.3f} | "
                f"{100 * row['wrong_share']:.1f} %"
            )
        else:
            lines.append(f"{band} | 0 | - | -")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", nargs="?", default="ipin2023")
    ap.add_argument("--seeds", default="7100-7299", help="FIRST-LAST")
    ap.add_argument("--severity", type=float, default=0.5, help="clutter severity (0: none)")
    ap.add_argument("--env", default="LRPRadarNavFast-v0", help="LRPRadarNav-v0: signal fidelity")
    ap.add_argument("--set", action="append", default=[], dest="sets", metavar="KEY=VALUE")
    ap.add_argument(
        "--agent-option", action="append", default=[], dest="agent_options", metavar="KEY=VALUE"
    )
    args = ap.parse_args()
    first, last = (int(s) for s in args.seeds.split("-"))
    over = overrides(args.scenario, args.sets)
    if args.severity > 0.0:  # 0: the unperturbed task
        over.setdefault("perturbations", {})["clutter"] = {"severity": args.severity}
    env = gym.make(args.env, scenario=args.scenario, task_mode="goal", overrides=over)
    policy = PurePursuitPolicy.from_env(env, **parse_options(args.agent_options))
    total_conv = total_wrong = stuck = 0
    confidences, errors_m = [], []
    for seed in range(first, last + 1):
        policy.reset()
        obs, _ = env.reset(seed=seed)
        steps = conv = wrong = run = longest = 0
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy.act(obs))
            done = terminated or truncated
            steps += 1
            confidences.append(float(info["localization_confidence"]))
            errors_m.append(float(info["position_error_m"]))
            is_wrong = bool(info["converged"]) and errors_m[-1] > WRONG_M
            conv += bool(info["converged"])
            wrong += is_wrong
            run = run + 1 if is_wrong else 0
            longest = max(longest, run)
        total_conv, total_wrong = total_conv + conv, total_wrong + wrong
        stuck += longest >= STUCK_FRAMES
        end = "truncated" if truncated else "terminated"
        print(
            f"seed {seed}: {steps} steps, {conv} converged, {wrong} wrong, longest {longest}, "
            f"{end} {info['position_error_m']:.2f} m off",
            flush=True,
        )
    episodes = last - first + 1
    print(
        f"{episodes} episodes: {total_wrong} of {total_conv} converged steps wrong "
        f"({100 * total_wrong / max(total_conv, 1):.1f} %), {stuck} stuck "
        f"(>= {STUCK_FRAMES} wrong converged steps in a row)"
    )
    print(reliability_table(np.array(confidences), np.array(errors_m)))


if __name__ == "__main__":
    main()
