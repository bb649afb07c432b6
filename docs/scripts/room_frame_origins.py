"""Why a converged estimate in a generated room is wrong, frame by frame (docs/trust.md,
session 28).

Pure pursuit on the default task in generated room ``ROOM`` (detections fidelity), episode
``SEED``: per frame the position error, the confidence, the gated distances' count, and the
log-likelihood of the frame's gated fingerprint at the true position minus at the estimate
(running sum). For the frames listed in ``--frames``, each gated distance with the strongest
channel paths within 5 cm of it at the true pose (kind: 0 direct, 1 a reflector via a face,
2 the room's surfaces), and what the likelihood sees at the truth and at the estimate: the
nearest expected reflector distance and the nearest map returns (S: structure, G: ghost row)
with their mixture weights.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/room_frame_origins.py 7 7004 --frames 9,10

Session 28 ran it on the code before the delivery survey in every room (commit 6e843de,
``git worktree add --detach DIR 6e843de``); on today's code the episodes differ.
"""

from __future__ import annotations

import argparse

import numpy as np

from agents.registry import make_agent
from lrp_gym.experiments.episodes import make_eval_env
from lrp_gym.experiments.scenarios import generated_room


def origins(base, frame_pose: np.ndarray, est_pose: np.ndarray, fp) -> list[str]:
    """One line per gated distance: its channel paths at the truth, and the model's view."""
    model = base.localizer.model
    returns = model.map_returns
    n_structure = 13 if returns.structure_probability > 0 else 0
    paths = base.core.stacks[0].sensor.paths(frame_pose, np.zeros(2))
    lines = []
    for z in np.concatenate(fp.distances_m):
        near = np.flatnonzero(np.abs(paths.range_m - z) <= 0.05)
        near = near[np.argsort(-paths.power_w[near])][:3]
        kinds = ", ".join(
            f"{int(paths.kind[i])} at {paths.range_m[i]:.3f} m {10 * np.log10(paths.power_w[i]):.0f} dBW"
            for i in near
        )
        line = f"  z = {z:.3f} m: paths [{kinds}]"
        for name, pose in (("truth", frame_pose), ("estimate", est_pose)):
            expected = np.concatenate(model.expected(pose[None, :2]))[:, 0]
            ranges = returns.ranges(pose[None, :2], None, np.float64)[0][:, 0]
            off = np.abs(ranges - z)
            best = np.argsort(off)[:2]
            rows = ", ".join(
                f"{'S' if k < n_structure else 'G'}{k} {off[k]:.3f} m w {returns.weights[k]:.4f}"
                for k in best
            )
            line += f" | {name}: reflector {np.min(np.abs(expected - z)):.3f} m off; {rows}"
        lines.append(line)
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("room", type=int)
    ap.add_argument("seed", type=int)
    ap.add_argument("--frames", default="", help="frames to list distance by distance, e.g. 9,10")
    ap.add_argument("--steps", type=int, default=40)
    args = ap.parse_args()
    listed = {int(f) for f in args.frames.split(",") if f}
    cfg = generated_room(args.room, {"radar": {"fidelity": "detections"}, "task": {"mode": "goal"}})
    env = make_eval_env("pure-pursuit", "LRPRadarNavFast-v0", scenario=cfg)
    policy = make_agent("pure-pursuit", env)
    base = env.unwrapped
    obs, _ = env.reset(seed=args.seed)
    policy.reset()
    total = 0.0
    for t in range(args.steps):
        obs, _, terminated, truncated, info = env.step(policy.act(obs))
        fp = base.tracker.gated_fingerprint()
        gap = np.nan
        if fp.count:
            model = base.localizer.model
            at_truth = model.log_likelihood(base.pose[None, :2].copy(), fp)[0]
            at_estimate = model.log_likelihood(base.estimate.pose[None, :2].copy(), fp)[0]
            gap = at_truth - at_estimate
            total += gap
        print(
            f"frame {t}: error {info['position_error_m']:.2f} m, confidence "
            f"{info['localization_confidence']:.3f}, {fp.count} distances, log-lik. truth - "
            f"estimate {gap:+.2f} (sum {total:+.1f})"
        )
        if t in listed and fp.count:
            print("\n".join(origins(base, base.pose.copy(), base.estimate.pose.copy(), fp)))
        if terminated or truncated:
            break


if __name__ == "__main__":
    main()
