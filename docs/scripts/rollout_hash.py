"""Hashes of fixed-seed rollouts: observations, rewards, true and estimated poses, particle
counts, per env id and scenario. Run it against two checkouts to check that a change keeps the
trajectories bit for bit (the speed work of issue #17):

```bash
PYTHONPATH=/work/main .venv/bin/python docs/scripts/rollout_hash.py > before.txt
PYTHONPATH=$PWD .venv/bin/python docs/scripts/rollout_hash.py > after.txt
diff before.txt after.txt && echo identical
```

Each rollout: ``reset(seed)``, then ``--steps`` steps of a seeded action stream (mostly forward,
turning), resetting (without a seed) when an episode ends, on the default task (sampled goals).
"""

from __future__ import annotations

import argparse
import hashlib

import gymnasium as gym
import numpy as np
import yaml

import lrp_gym  # noqa: F401  (registers the ids)

CASES = (
    ("LRPRadarNavFast-v0", "ipin2023"),
    ("LRPRadarNavFast-v0", "ipin2023-2types"),
    ("LRPRadarNav-v0", "ipin2023"),
)


def _overrides(sets: list[str]) -> dict:
    """``KEY.PATH=VALUE`` settings (values read as YAML) as a nested dict, on the goal task."""
    out: dict = {"task": {"mode": "goal"}}
    for item in sets:
        path, value = item.split("=", 1)
        *parents, leaf = path.split(".")
        node = out
        for key in parents:
            node = node.setdefault(key, {})
        node[leaf] = yaml.safe_load(value)
    return out


def rollout_hash(env_id: str, scenario: str, steps: int, seed: int, sets: list[str]) -> str:
    """SHA-256 over every step's observation, reward, flags, poses and particle count."""
    env = gym.make(env_id, scenario=scenario, overrides=_overrides(sets))
    rng = np.random.default_rng(seed)
    h = hashlib.sha256()
    obs, info = env.reset(seed=seed)
    h.update(np.asarray(obs).tobytes())
    for _ in range(steps):
        action = np.array([rng.uniform(0.2, 0.8), rng.uniform(-0.4, 0.4)], dtype=np.float32)
        obs, reward, terminated, truncated, info = env.step(action)
        h.update(np.asarray(obs).tobytes())
        h.update(np.float64(reward).tobytes())
        h.update(bytes([terminated, truncated]))
        h.update(np.asarray(info["true_pose"], dtype=float).tobytes())
        h.update(np.asarray(info["est_pose"], dtype=float).tobytes())
        h.update(np.int64(info["n_particles"]).tobytes())
        h.update(np.float64(info["localization_confidence"]).tobytes())
        if terminated or truncated:
            obs, info = env.reset()
            h.update(np.asarray(obs).tobytes())
    env.close()
    return h.hexdigest()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--seed", type=int, default=11)
    parser.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE")
    args = parser.parse_args()
    for env_id, scenario in CASES:
        digest = rollout_hash(env_id, scenario, args.steps, args.seed, args.set)
        print(env_id, scenario, digest, flush=True)


if __name__ == "__main__":
    main()
