"""``lrp_gym.envs.bench``: the env speed benchmark runs on any valid scenario."""

from __future__ import annotations

import lrp_gym  # noqa: F401  (registers the env ids)
from lrp_gym.envs import bench


def test_fixed_particle_row_runs_on_a_scenario_that_starts_with_fewer(paper_cfg, monkeypatch):
    # The row raised min_particles to 10000 but kept initial_particles: a valid scenario that
    # starts with 500 failed validation (`lrp-gym bench -c env` blamed the user's file).
    loc = {"initial_particles": 500, "min_particles": 100, "max_particles": 500}
    cfg = paper_cfg.with_overrides({"localization": loc})
    monkeypatch.setattr(bench, "ENV_VARIANTS", ())  # only the fixed row
    out = bench.bench_envs(cfg, 0.1)["variants"]
    assert list(out) == ["LRPRadarNav-v0 (fixed 10000 particles)"]
    assert out["LRPRadarNav-v0 (fixed 10000 particles)"]["steps_per_s"] > 0
