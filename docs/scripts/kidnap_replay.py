"""Replay single kidnapping episodes of the patrol and say how each ended (session 10).

A kidnap counts as not recovered within 15 frames also when the episode ends first. This
prints, per seed, the kidnap frame, the episode's length, whether it ended in a collision and
after how many frames the error was below 0.2 m again (None: never).

```bash
PYTHONPATH=$PWD .venv/bin/python docs/scripts/kidnap_replay.py 5,25 1 \
    localization.initial_particles=2000 localization.start_grid_m=0.1
```

Arguments: seeds (comma-separated), severity, then ``KEY.PATH=VALUE`` settings; the
scenario is ``ipin2023-patrol`` unless ``--scenario NAME`` comes first.
"""

from __future__ import annotations

import sys

import lrp_gym  # noqa: F401  (registers the ids)
from lrp_gym.commands._common import overrides
from lrp_gym.experiments import episodes as ep
from lrp_gym.experiments.robustness import recovery_frames


def main() -> None:
    from agents import registry

    args = sys.argv[1:]
    scenario = "ipin2023-patrol"
    if args[0] == "--scenario":
        scenario, args = args[1], args[2:]
    seeds = [int(s) for s in args[0].split(",")]
    severity, sets = args[1], args[2:]
    kidnap = [f"perturbations.kidnapping.severity={severity}"]
    over = overrides(scenario, kidnap + sets, "detections")
    env = ep.make_eval_env("pure-pursuit", None, scenario, overrides=over)
    policy = registry.make_agent("pure-pursuit", env)
    for seed in seeds:
        r = ep.run_episode(env, policy, seed)
        rec = recovery_frames(r.loc_error_m, r.kidnap_frame)
        print(
            f"sev {severity} seed {seed}: kidnap frame {r.kidnap_frame}, episode {r.steps} frames,"
            f" collision {r.collision}, recovered after {rec},"
            f" frames after kidnap {r.steps - r.kidnap_frame + 1}",
            flush=True,
        )


if __name__ == "__main__":
    main()
