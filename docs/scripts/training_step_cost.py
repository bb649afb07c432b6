"""What a step costs under the actions PPO training produces (issue #17, session 12).

`lrp-gym bench` drives the env with uniform random actions; PPO's rollouts come from its
policy: at the start a Gaussian about zero (``log_std_init=-1``: std 0.37 in the normalised
action space), at the end the trained policy, whose episodes reach their goal in about 8 steps.
Both spend a larger share of their steps in an episode's first frames (global localisation),
which cost several converged frames each. This prints, for each action source on
``LRPRadarNavFast-v0``'s default task, steps per CPU second, the mean episode length, and per
phase of the episode (the reset's frame, steps 1, 2, 3, later steps) the CPU milliseconds, the
share of the CPU time and the mean particle count after the step.

```bash
PYTHONPATH=$PWD .venv/bin/python docs/scripts/training_step_cost.py --steps 600
```

Sources: ``uniform`` (the bench's), ``untrained`` (Gaussian, std 0.37 about 0, clipped),
``shipped`` (the shipped PPO model, sampling as in training: ``deterministic=False``).
``--loc KEY=VALUE`` sets a ``localization`` setting (e.g. ``initial_particles=2000``).
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np
import yaml

import lrp_gym  # noqa: F401  (registers the ids)

PHASES = ("reset", "1", "2", "3", "later")


def action_source(name: str, env: gym.Env, rng: np.random.Generator):
    """``act(observation) -> action`` for a source name."""
    if name == "uniform":
        return lambda obs: rng.uniform(-1.0, 1.0, 2).astype(np.float32)
    if name == "untrained":
        return lambda obs: np.clip(rng.normal(0.0, np.exp(-1.0), 2), -1, 1).astype(np.float32)
    from agents.registry import load_ppo

    policy = load_ppo(None, (env.observation_space, env.action_space))
    return lambda obs: policy.predict(obs[None], deterministic=False)[0][0]


def phase_costs(
    source: str, steps: int, seed: int = 0, localization: dict | None = None
) -> tuple[dict, dict, list[int]]:
    """Per phase: CPU seconds and particle counts of each step; and the episode lengths."""
    overrides = {"localization": localization} if localization else None
    env = gym.make("LRPRadarNavFast-v0", overrides=overrides)
    act = action_source(source, env, np.random.default_rng(seed))
    cpu = {p: [] for p in PHASES}
    particles = {p: [] for p in PHASES}
    lengths = []
    c0 = time.process_time()
    obs, info = env.reset(seed=seed)
    cpu["reset"].append(time.process_time() - c0)
    particles["reset"].append(info["n_particles"])
    k = 0
    for _ in range(steps):
        action = act(obs)
        c0 = time.process_time()
        obs, _, terminated, truncated, info = env.step(action)
        k += 1
        phase = str(k) if k <= 3 else "later"
        cpu[phase].append(time.process_time() - c0)
        particles[phase].append(info["n_particles"])
        if terminated or truncated:
            lengths.append(k)
            c0 = time.process_time()
            obs, info = env.reset()
            cpu["reset"].append(time.process_time() - c0)
            particles["reset"].append(info["n_particles"])
            k = 0
    env.close()
    return cpu, particles, lengths


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=600)
    parser.add_argument("--sources", default="uniform,untrained,shipped")
    parser.add_argument("--loc", action="append", default=[], metavar="KEY=VALUE")
    args = parser.parse_args()
    settings = {k: yaml.safe_load(v) for k, v in (item.split("=", 1) for item in args.loc)}
    for source in args.sources.split(","):
        cpu, particles, lengths = phase_costs(source, args.steps, localization=settings)
        total = sum(sum(v) for v in cpu.values())
        mean_len = np.mean(lengths) if lengths else float("nan")
        print(
            f"{source}: {args.steps / total:.1f} steps per CPU second,"
            f" {len(lengths)} episodes ended, mean length {mean_len:.1f} steps"
        )
        for p in PHASES:
            if cpu[p]:
                print(
                    f"  {p:>6}: {1e3 * np.mean(cpu[p]):6.2f} ms x {len(cpu[p]):4d}"
                    f"  ({sum(cpu[p]) / total:5.1%} of the CPU time),"
                    f" {np.mean(particles[p]):7.0f} particles"
                )


if __name__ == "__main__":
    main()
