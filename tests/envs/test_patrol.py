"""Patrol tasks: a closed path driven ``task.laps`` times, truncated at the scenario's limit."""

from __future__ import annotations

from dataclasses import replace

import gymnasium as gym
import numpy as np
import pytest

from lrp_gym.config import ScenarioError, load_scenario
from lrp_gym.envs import nav_batch
from lrp_gym.experiments.episodes import nav_env

PATROLS = ("ipin2023-patrol", "ipin2023-2types-patrol")


def test_laps_need_a_closed_path():
    cfg = load_scenario("ipin2023")  # the paper path ends at (2.25, 3.25), not at its start
    with pytest.raises(ScenarioError, match=r"task\.laps: 3 laps need a closed task\.path"):
        cfg.with_overrides({"task": {"laps": 3}})
    with pytest.raises(ScenarioError, match=r"task\.laps"):
        cfg.with_overrides({"task": {"laps": 0}})
    with pytest.raises(ScenarioError, match=r"task\.max_episode_steps"):
        cfg.with_overrides({"task": {"max_episode_steps": 0}})


def test_driven_path_repeats_the_loop_without_doubling_the_joints():
    task = load_scenario("ipin2023-patrol").task
    loop = np.asarray(task.path)
    driven = task.driven_path()
    assert task.closed and task.laps >= 2
    assert len(driven) == task.laps * (len(loop) - 1) + 1
    assert np.allclose(driven[len(loop) - 1 :][: len(loop)], loop)  # lap two starts where one ends
    steps = np.linalg.norm(np.diff(driven, axis=0), axis=1)
    assert steps.min() > 0.0  # no zero-length segment at a lap joint


@pytest.mark.parametrize("name", PATROLS)
def test_patrol_is_long_and_not_cut_by_a_time_limit(name):
    cfg = load_scenario(name)
    loop = np.asarray(cfg.task.path)
    lap_m = float(np.sum(np.linalg.norm(np.diff(loop, axis=0), axis=1)))
    # At top speed, one frame covers max_speed * frame_period of the path.
    min_frames = cfg.task.laps * lap_m / (cfg.robot.max_speed_mps * cfg.task.frame_period_s)
    assert min_frames >= 120
    assert cfg.task.max_episode_steps >= 1.5 * min_frames
    env = gym.make("LRPRadarNavFast-v0", scenario=name)
    try:
        env.reset(seed=0)
        base = nav_env(env)
        assert base.path.length_m == pytest.approx(cfg.task.laps * lap_m)
        assert env.spec.max_episode_steps is None  # the env truncates, at the scenario's limit
    finally:
        env.close()


def test_env_truncates_at_the_scenarios_step_limit():
    env = gym.make(
        "LRPRadarNavFast-v0",
        scenario="ipin2023-patrol",
        overrides={"task": {"max_episode_steps": 3}},
    )
    try:
        env.reset(seed=0)
        flags = [env.step(np.zeros(2))[3] for _ in range(3)]  # standing still: never done
        assert flags == [False, False, True]
    finally:
        env.close()


@pytest.mark.parametrize("name", ["ipin2023-patrol", "ipin2023"])
def test_progress_starts_at_the_start_of_the_path(name):
    # The start is also the end of every lap of a patrol, and the first estimate of a global
    # localisation (uniform init) lies anywhere: progress must start near 0 (seed 1: the first
    # estimate projected 9 m along the path before).
    env = gym.make("LRPRadarNavFast-v0", scenario=name)
    try:
        env.reset(seed=1)
        base = nav_env(env)
        assert base.cfg.localization.init == "uniform"
        assert base.core.s_true_m[0] == pytest.approx(0.0)
        assert base.core.s_est_m[0] <= 3.0 < base.path.length_m / base.cfg.task.laps
    finally:
        env.close()


def test_estimated_progress_advances_no_faster_than_the_odometry(monkeypatch):
    """A wrong estimate (here: forced to the far side of the loop every frame) may not carry
    the estimated progress further than the reported odometry plus the slack: on a patrol it
    used to run a lap ahead of the robot, which then stopped a lap early (a timeout)."""
    env = gym.make("LRPRadarNavFast-v0", scenario="ipin2023-2types-patrol")
    try:
        env.reset(seed=0)
        base = nav_env(env)
        core = base.core
        far = np.array([*np.asarray(base.cfg.task.path)[7], 0.0])
        real_estimate = core.estimate
        monkeypatch.setattr(core, "estimate", lambda i: replace(real_estimate(i), pose=far))
        driven: list[float] = []
        real_odometry = nav_batch.noisy_odometry

        def spy(*args, **kwargs):
            odo = real_odometry(*args, **kwargs)
            driven.append(abs(float(odo[1])))
            return odo

        monkeypatch.setattr(nav_batch, "noisy_odometry", spy)
        gains = []
        for _ in range(8):
            before = float(core.s_est_m[0])
            env.step(np.array([1.0, 0.0], dtype=np.float32))
            gains.append(float(core.s_est_m[0]) - before)
        slack = nav_batch._PROGRESS_SLACK_M
        assert all(g <= d + slack + 1e-9 for g, d in zip(gains, driven, strict=True))
        assert sum(gains) > 1.0  # it does follow the estimate, as fast as the robot drives
    finally:
        env.close()
