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


class _ShortEpisodes:
    """An env whose episodes end every third step and that refuses a step after the end."""

    def __init__(self) -> None:
        self.t, self.ended, self.resets = 0, False, 0

    def reset(self, seed=None):
        self.t, self.ended = 0, False
        self.resets += 1
        return None, {}

    def step(self, action):
        assert not self.ended, "stepped an ended episode"
        self.t += 1
        self.ended = self.t % 3 == 0
        return None, 0.0, self.ended, False, {}


def test_converged_rate_never_steps_an_ended_episode():
    # In a small room the circling robot reaches a wall within the warm-up: the warm-up
    # stepped on after the episode's end (gymnasium warns; the env's state is undefined).
    env = _ShortEpisodes()
    assert bench.converged_steps_per_s(env, 0.01, warmup_steps=10) > 0
    assert env.resets > 3
