"""Per-episode traces of one robustness cell: why do its episodes fail?

Runs one cell (pure pursuit, detections fidelity, seeds 0..N-1) and prints, per episode:
success, collision, steps, share of steps localised, confidently wrong steps (converged and
off by > 0.3 m) and their longest stretch, the largest error, the reflectors named suspect
(and the first frame) and where the robot and its estimate ended. ``--oracle-clutter-map``
hands the localiser's clutter map the scatterers' true positions (and stops its learning):
the yardstick of what a perfect clutter map could do (it switches the map on).

    python docs/scripts/cell_traces.py ipin2023-2types-patrol clutter 0.5 50 \
        ['{"localization": {"max_random_fraction": 0.0}}'] [--oracle-clutter-map]
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from agents.registry import make_agent
from lrp_gym.config import deep_merge
from lrp_gym.experiments.episodes import episode_results, make_eval_env
from lrp_gym.experiments.robustness import cell_overrides


def oracle_clutter_map() -> None:
    """Every clutter map gets the clutter perturbation's true scatterers at each reset."""
    from lrp_gym.localization import clutter_map as cmm
    from lrp_gym.perturbations.sensing import Clutter

    maps: list[cmm.ClutterMap] = []
    post, on_reset = cmm.ClutterMap.__post_init__, Clutter.on_reset

    def track(self) -> None:
        post(self)
        maps.append(self)

    def reset(self, ctx, rng) -> None:
        on_reset(self, ctx, rng)
        for m in maps:
            m.reset()
            for p in self.positions_m:
                m.add(np.array([p[0], p[1], abs(p[2] - self.world.mount_height_m)]))

    cmm.ClutterMap.__post_init__ = track
    cmm.ClutterMap.update = lambda self, *a, **k: None  # no learning, no forgetting
    Clutter.on_reset = reset


def trace_row(r) -> dict:
    e = r.loc_error_m
    wrong = r.converged & (e > 0.3)
    run = longest = 0
    for v in wrong:
        run = run + 1 if v else 0
        longest = max(longest, run)
    return {
        "seed": r.seed,
        "success": bool(r.success),
        "collision": bool(r.collision),
        "steps": r.steps,
        "localised": round(float(np.mean(e < 0.2)), 3),
        "wrong_steps": int(wrong.sum()),
        "wrong_longest": longest,
        "err_max_m": round(float(e.max()), 2),
        "suspects": {int(k): int(v) for k, v in r.suspect_first_frame.items()},
        "end_true": [round(float(x), 2) for x in r.true_xy[-1]],
        "end_est": [round(float(x), 2) for x in r.est_xy[-1]],
    }


def main(argv: list[str]) -> None:
    flags = [a for a in argv if a.startswith("--")]
    args = [a for a in argv if not a.startswith("--")]
    scenario, name, severity, episodes = args[0], args[1], float(args[2]), int(args[3])
    extra = json.loads(args[4]) if len(args) > 4 else {}
    if "--oracle-clutter-map" in flags:
        oracle_clutter_map()
        extra = deep_merge(extra, {"localization": {"clutter_map": {"enabled": True}}})
    overrides = deep_merge(extra, cell_overrides(name, severity))
    env = make_eval_env("pure-pursuit", "LRPRadarNavFast-v0", scenario, overrides=overrides or None)
    policy = make_agent("pure-pursuit", env)
    t0 = time.perf_counter()
    rows = [trace_row(r) for r in episode_results(env, policy, list(range(episodes)))]
    for row in rows:
        print(json.dumps(row))
    n = len(rows)
    summary = {
        "episodes": n,
        "success": sum(r["success"] for r in rows),
        "collisions": sum(r["collision"] for r in rows),
        "localised": round(float(np.mean([r["localised"] for r in rows])), 3),
        "wrong_steps": sum(r["wrong_steps"] for r in rows),
        "naming_a_suspect": sum(bool(r["suspects"]) for r in rows),
        "wall_s": round(time.perf_counter() - t0, 1),
    }
    print(json.dumps(summary))


if __name__ == "__main__":
    main(sys.argv[1:])
