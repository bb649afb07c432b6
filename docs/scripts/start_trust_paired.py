"""Paired trust comparison of filter settings on the default task (issue #17, session 10).

The trust rows (``lrp-gym evaluate --agent pure-pursuit --task goal --fidelity detections``)
pool about 1 000 steps over 100 episodes; a change to the global start moves a few of them.
This script runs the same episodes (same seeds: same start, goal and radar draws up to the
filter's own random numbers) under several settings, keeps per-episode counts, and gives the
difference of each pooled rate against the first setting with a 95 % bootstrap interval over
episodes (paired: one resample of seeds for all settings).

```bash
PYTHONPATH=$PWD .venv/bin/python docs/scripts/start_trust_paired.py ipin2023 \
    --episodes 500 --seed 7000 --out runs.json \
    --variant base= --variant ip2000=localization.initial_particles=2000
PYTHONPATH=$PWD .venv/bin/python docs/scripts/start_trust_paired.py --compare runs.json
```

A ``--variant NAME=KEY=VALUE,KEY=VALUE`` with an empty list is the scenario's defaults.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

import lrp_gym  # noqa: F401  (registers the ids)
from lrp_gym.localization.metrics import CONFIDENTLY_WRONG_M, LOCALISED_M

COUNTS = ("steps", "localised", "converged", "wrong", "success", "first4_localised")


def episode_counts(
    scenario: str, sets: list[str], episodes: int, seed: int, warmup: int = 0
) -> dict[str, list]:
    """Per-episode step counts of one setting (see :data:`COUNTS`) and ``cpu_s``, the
    process CPU seconds of its episodes (after ``warmup`` untimed episodes on other seeds:
    the compiled kernels are built on first use)."""
    from agents import registry
    from lrp_gym.commands._common import overrides
    from lrp_gym.config import deep_merge
    from lrp_gym.experiments import episodes as ep

    over = deep_merge(overrides(scenario, sets, "detections"), {"task": {"mode": "goal"}})
    env = ep.make_eval_env("pure-pursuit", None, scenario, overrides=over)
    policy = registry.make_agent("pure-pursuit", env)
    out: dict[str, list] = {k: [] for k in COUNTS}
    ep.episode_results(env, policy, list(range(seed + 10**6, seed + 10**6 + warmup)), 1, None)
    c0 = time.process_time()
    results = ep.episode_results(env, policy, list(range(seed, seed + episodes)), 1, None)
    out["cpu_s"] = [time.process_time() - c0]
    for r in results:
        loc = r.loc_error_m < LOCALISED_M
        out["steps"].append(int(r.steps))
        out["localised"].append(int(loc.sum()))
        out["converged"].append(int(r.converged.sum()))
        out["wrong"].append(int((r.converged & (r.loc_error_m > CONFIDENTLY_WRONG_M)).sum()))
        out["success"].append(int(r.success))
        out["first4_localised"].append(int(loc[:4].sum()))
    env.close()
    return out


def rates(c: dict[str, np.ndarray], idx: np.ndarray) -> dict[str, float]:
    """Pooled rates over the episodes ``idx``: localised and first-4-frames localised share
    of steps, confidently wrong share of converged steps, success share of episodes."""
    s = {k: c[k][idx].sum(axis=-1) for k in COUNTS}
    first4 = np.minimum(c["steps"], 4)[idx].sum(axis=-1)
    return {
        "localised": s["localised"] / s["steps"],
        "confidently_wrong": s["wrong"] / np.maximum(s["converged"], 1),
        "success": s["success"] / idx.shape[-1],
        "localised_first4": s["first4_localised"] / first4,
    }


def compare(runs: dict[str, dict[str, list]], n_boot: int = 2000, seed: int = 0) -> None:
    """Print each setting's rates and its paired difference to the first setting."""
    names = list(runs)
    arrays = {v: {k: np.asarray(runs[v][k]) for k in COUNTS} for v in names}
    n = len(arrays[names[0]]["steps"])
    boot = np.random.default_rng(seed).integers(0, n, size=(n_boot, n))
    full = np.arange(n)
    base = rates(arrays[names[0]], full)
    base_boot = rates(arrays[names[0]], boot)
    for v in names:
        point = rates(arrays[v], full)
        vb = rates(arrays[v], boot)
        cells = []
        for k, value in point.items():
            lo, hi = np.percentile(vb[k], [2.5, 97.5])
            d_lo, d_hi = np.percentile(vb[k] - base_boot[k], [2.5, 97.5])
            cells.append(
                f"{k} {100 * value:.2f} % ({100 * lo:.2f}-{100 * hi:.2f});"
                f" diff {100 * (value - base[k]):+.2f} ({100 * d_lo:+.2f} to {100 * d_hi:+.2f})"
            )
        steps = int(arrays[v]["steps"].sum())
        cpu = runs[v].get("cpu_s", [float("nan")])[0]
        print(f"{v} ({n} episodes, {steps} steps, {steps / cpu:.1f} steps per CPU second)")
        for cell in cells:
            print("   " + cell)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", nargs="?", default="ipin2023")
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--seed", type=int, default=7000)
    parser.add_argument("--variant", action="append", default=[], metavar="NAME=SETS")
    parser.add_argument("--warmup", type=int, default=0, help="untimed episodes first")
    parser.add_argument("--out", help="write the per-episode counts here (JSON)")
    parser.add_argument("--compare", nargs="+", help="JSON files to compare (first: reference)")
    args = parser.parse_args()
    runs: dict[str, dict[str, list]] = {}
    for path in args.compare or []:
        with open(path) as f:
            runs.update(json.load(f))
    for item in args.variant:
        name, _, sets = item.partition("=")
        runs[name] = episode_counts(
            args.scenario, [s for s in sets.split(",") if s], args.episodes, args.seed, args.warmup
        )
        if args.out:
            with open(args.out, "w") as f:
                json.dump(runs, f)
    compare(runs)


if __name__ == "__main__":
    main()
