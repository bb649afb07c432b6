"""CPU time of fixed, seeded workloads: a speed comparison that survives a loaded machine.

``lrp-gym bench`` reports wall-clock rates, which on a shared machine move with the other
processes' load. When two checkouts produce the same trajectories (check with
``rollout_hash.py``), the same seeded workload is the same work, and the ratio of the process
CPU times is the speed-up. Each workload runs in a fresh process per checkout, alternating,
and the fastest of ``--repeats`` counts:

```bash
.venv/bin/python docs/scripts/cpu_time_compare.py --before /work/main --after $PWD
```

Workloads: the single env (both fidelities) for ``--steps`` steps after a reset, and the
vector env with N = ``--num-envs`` robots for ``--batch-steps`` steps, both on the default task
(sampled goals, next-step autoreset), with the seeded action stream of ``rollout_hash.py``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

WORKLOADS = ("single:detections", "single:signal", "vector:detections", "vector:signal")


def _actions(rng, n: int):
    import numpy as np

    return np.column_stack([rng.uniform(0.2, 0.8, n), rng.uniform(-0.4, 0.4, n)]).astype(np.float32)


def run_workload(name: str, steps: int, num_envs: int, batch_steps: int) -> dict:
    """CPU seconds of one workload in this process (construction and warm-up excluded)."""
    import gymnasium as gym
    import numpy as np

    import lrp_gym  # noqa: F401  (registers the ids)
    from lrp_gym.envs.vector_env import LRPRadarNavVectorEnv

    kind, fidelity = name.split(":")
    overrides = {"task": {"mode": "goal"}, "radar": {"fidelity": fidelity}}
    rng = np.random.default_rng(11)
    if kind == "single":
        env = gym.make("LRPRadarNav-v0", overrides=overrides)
        env.reset(seed=1)
        for _ in range(5):  # warm-up: compiled kernels loaded, caches filled
            env.step(_actions(rng, 1)[0])
        env.reset(seed=11)
        t0 = time.process_time()
        for _ in range(steps):
            _, _, terminated, truncated, _ = env.step(_actions(rng, 1)[0])
            if terminated or truncated:
                env.reset()
        return {"cpu_s": time.process_time() - t0, "robot_steps": steps}
    from lrp_gym.envs.nav_env import build_config

    venv = LRPRadarNavVectorEnv(num_envs, scenario=build_config(None, overrides))
    venv.reset(seed=1)
    venv.step(_actions(rng, num_envs))
    venv.reset(seed=11)
    t0 = time.process_time()
    for _ in range(batch_steps):
        venv.step(_actions(rng, num_envs))
    return {"cpu_s": time.process_time() - t0, "robot_steps": batch_steps * num_envs}


def _in_process(checkout: str, name: str, args) -> dict:
    env = {**os.environ, "PYTHONPATH": checkout}
    cmd = [sys.executable, __file__, "--worker", name, "--steps", str(args.steps)]
    cmd += ["--num-envs", str(args.num_envs), "--batch-steps", str(args.batch_steps)]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True, cwd=checkout)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", default="/work/main")
    parser.add_argument("--after", default=os.getcwd())
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--num-envs", type=int, default=64)
    parser.add_argument("--batch-steps", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--only", default=",".join(WORKLOADS))
    parser.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(run_workload(args.worker, args.steps, args.num_envs, args.batch_steps)))
        return
    results = {}
    for name in args.only.split(","):
        best: dict[str, float] = {}
        for _ in range(args.repeats):
            for tag, checkout in (("before", args.before), ("after", args.after)):
                r = _in_process(checkout, name, args)
                rate = r["robot_steps"] / r["cpu_s"]
                best[tag] = max(best.get(tag, 0.0), rate)
        results[name] = {
            "before_steps_per_cpu_s": best["before"],
            "after_steps_per_cpu_s": best["after"],
            "speedup": best["after"] / best["before"],
        }
        print(name, json.dumps(results[name]), flush=True)
    print(json.dumps({"load_avg_1min": os.getloadavg()[0], "workloads": results}))


if __name__ == "__main__":
    main()
