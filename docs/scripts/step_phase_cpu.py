"""CPU time of the single env per step by phase of the episode, and the fixed per-robot part.

Where a robot-step's time goes decides what batching robots can buy (issue #17): a batch shares
the per-call cost of a frame among its robots, not the arithmetic over particles and grid
cells. This script runs the seeded action stream of ``rollout_hash.py`` on the default task
and prints, per step of an episode (the reset's first frame, steps 1, 2, 3, then every later
step), the mean CPU milliseconds and the share of the run. It then runs the same stream with
a tiny filter (20 particles, a 1 m lost-test grid): what a converged step costs then is the
part that does not scale with the particles and cells, i.e. the most a batch could share.

```bash
PYTHONPATH=$PWD .venv/bin/python docs/scripts/step_phase_cpu.py --steps 600
```

``--loc KEY=VALUE`` sets a ``localization`` setting for the default filter's run (e.g.
``initial_particles=2000``: what a cheaper global start would buy; other trajectories).
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np
import yaml

import lrp_gym  # noqa: F401  (registers the ids)

TINY = {"initial_particles": 20, "min_particles": 10, "max_particles": 20, "global_grid_m": 1.0}


def phase_cpu_ms(fidelity: str, steps: int, localization: dict | None = None) -> dict[str, list]:
    """CPU seconds of every step, keyed by phase (``reset``, ``1``, ``2``, ``3``, ``later``)."""
    overrides = {"task": {"mode": "goal"}, "radar": {"fidelity": fidelity}}
    if localization:
        overrides["localization"] = localization
    env = gym.make("LRPRadarNav-v0", overrides=overrides)
    rng = np.random.default_rng(11)
    env.reset(seed=1)
    out: dict[str, list] = {"reset": [], "1": [], "2": [], "3": [], "later": []}
    k = 0
    for _ in range(steps):
        action = np.array([rng.uniform(0.2, 0.8), rng.uniform(-0.4, 0.4)], dtype=np.float32)
        c0 = time.process_time()
        _, _, terminated, truncated, _ = env.step(action)
        k += 1
        out[str(k) if k <= 3 else "later"].append(time.process_time() - c0)
        if terminated or truncated:
            c0 = time.process_time()
            env.reset()
            out["reset"].append(time.process_time() - c0)
            k = 0
    env.close()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=600)
    parser.add_argument("--fidelity", default="detections")
    parser.add_argument("--loc", action="append", default=[], metavar="KEY=VALUE")
    args = parser.parse_args()
    settings = {k: yaml.safe_load(v) for k, v in (item.split("=", 1) for item in args.loc)}
    for label, loc in (("default filter", settings), ("tiny filter", TINY)):
        phases = phase_cpu_ms(args.fidelity, args.steps, loc)
        total = sum(sum(v) for v in phases.values())
        print(f"{label}: {args.steps / total:.1f} steps per CPU second")
        for name, times in phases.items():
            if times:
                print(
                    f"  {name:>6}: {1e3 * np.mean(times):6.2f} ms x {len(times):4d}"
                    f"  ({sum(times) / total:5.1%} of the CPU time)"
                )


if __name__ == "__main__":
    main()
