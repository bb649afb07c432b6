"""LRPRadarNav-v0: API conformance, determinism, termination, estimate-only observations."""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import lrp_gym  # noqa: F401  (registers the envs)
from lrp_gym.envs.nav_env import LRPRadarNavEnv
from lrp_gym.localization.pose_estimate import PoseEstimate

FAST = {"radar_fidelity": "detections"}


def rollout(env, seed: int, n: int = 15, action=(0.4, 0.2)):
    obs, info = env.reset(seed=seed)
    traj = [np.concatenate([info["true_pose"], info["est_pose"], obs])]
    for _ in range(n):
        obs, _, term, trunc, info = env.step(np.array(action, dtype=np.float32))
        traj.append(np.concatenate([info["true_pose"], info["est_pose"], obs]))
        if term or trunc:
            break
    return np.array(traj)


@pytest.mark.parametrize("env_id", ["LRPRadarNav-v0", "LRPRadarNavFast-v0"])
def test_gymnasium_check_env_with_render(env_id):
    env = gym.make(env_id, render_mode="rgb_array")
    check_env(env.unwrapped, skip_render_check=False)
    env.close()


def test_sb3_check_env():
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = LRPRadarNavEnv(**FAST)
    sb3_check_env(env, warn=True)


@pytest.mark.parametrize("kwargs", [{}, FAST])
def test_same_seed_same_trajectory_different_seed_differs(kwargs):
    a = rollout(LRPRadarNavEnv(**kwargs), seed=3)
    b = rollout(LRPRadarNavEnv(**kwargs), seed=3)
    c = rollout(LRPRadarNavEnv(**kwargs), seed=4)
    assert np.array_equal(a, b)
    assert a.shape != c.shape or not np.allclose(a, c)


def test_collision_terminates_with_penalty():
    env = LRPRadarNavEnv(task_mode="path", **FAST)
    env.reset(seed=0)
    # Start at (0.75, 0.75) facing +x; turn to face -x (the wall at x = 0) and drive into it.
    env.unwrapped.pose = np.array([0.75, 0.75, np.pi])
    for _ in range(10):
        _, reward, term, _, info = env.step(np.array([1.0, 0.0], dtype=np.float32))
        if term:
            break
    assert term and info["collision"] and not info["is_success"]
    assert info["rewards"]["collision"] < 0
    assert env.world.room.free(info["true_pose"][None, :2], env.world.robot.radius_m)[0]


def test_goal_terminates_with_bonus():
    env = LRPRadarNavEnv("ipin2023", {"task": {"path": [[0.75, 0.75], [1.25, 0.75]]}}, **FAST)
    env.reset(seed=0)
    _, reward, term, _, info = env.step(np.array([0.5, 0.0], dtype=np.float32))
    assert term and info["is_success"] and not info["collision"]
    assert info["rewards"]["goal"] > 0
    # 0.5 x 2 m/s x 0.25 s = 0.25 m driven straight along the path.
    assert info["rewards"]["progress"] == pytest.approx(0.25, abs=0.02)
    assert reward == pytest.approx(sum(info["rewards"].values()))


def test_observation_depends_on_estimate_not_truth():
    env = LRPRadarNavEnv(**FAST)
    env.reset(seed=1)
    for _ in range(3):
        env.step(np.array([0.2, 0.0], dtype=np.float32))
    base = env._observe()
    true_pose = env.pose.copy()
    env.pose = true_pose + np.array([0.5, -0.3, 0.4])  # the truth alone moves
    assert np.array_equal(env._observe(), base)
    env.pose = true_pose
    est = env.estimate
    env.estimate = PoseEstimate(
        est.pose + np.array([0.3, 0.2, 0.1]),
        est.covariance,
        est.n_particles,
        est.ess,
        est.converged,
    )
    assert not np.allclose(env._observe(), base)


def test_oracle_observation_follows_the_truth():
    env = LRPRadarNavEnv(observation="oracle", **FAST)
    env.reset(seed=1)
    base = env._observe()
    env.pose = env.pose + np.array([0.3, 0.0, 0.0])
    assert not np.allclose(env._observe(), base)


def test_dict_observation_space():
    env = LRPRadarNavEnv(observation="dict", **FAST)
    obs, _ = env.reset(seed=0)
    assert isinstance(env.observation_space, gym.spaces.Dict)
    assert env.observation_space.contains(obs)


def test_actions_are_validated():
    env = LRPRadarNavEnv(**FAST)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([np.nan, 0.0]))
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros(3))
    # Out-of-box actions are clipped, not rejected.
    _, _, _, _, info = env.step(np.array([5.0, -7.0], dtype=np.float32))
    assert np.isfinite(info["true_pose"]).all()


def test_info_contents_and_float32_observation():
    env = LRPRadarNavEnv(**FAST)
    obs, info = env.reset(seed=0)
    assert obs.dtype == np.float32 and env.observation_space.contains(obs)
    for key in (
        "true_pose",
        "est_pose",
        "position_error_m",
        "heading_error_rad",
        "pose_std",
        "n_particles",
        "ess",
        "n_detections",
        "converged",
        "rewards",
    ):
        assert key in info
    assert info["n_particles"] > 0


def test_render_rgb_array():
    env = LRPRadarNavEnv(render_mode="rgb_array", **FAST)
    env.reset(seed=0)
    env.step(env.action_space.sample())
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    assert frame.shape[0] >= 100 and frame.std() > 0
    env.close()


def test_env_pickles_and_keeps_state():
    env = LRPRadarNavEnv(**FAST)
    env.reset(seed=2)
    env.step(np.array([0.3, 0.1], dtype=np.float32))
    clone = pickle.loads(pickle.dumps(env))
    a = clone.step(np.array([0.3, 0.1], dtype=np.float32))
    b = env.step(np.array([0.3, 0.1], dtype=np.float32))
    assert np.array_equal(a[0], b[0]) and a[1] == b[1]


def test_sync_and_async_vector_envs_step():
    fns = [lambda: gym.make("lrp_gym:LRPRadarNavFast-v0") for _ in range(2)]
    for vec in (gym.vector.SyncVectorEnv(fns), gym.vector.AsyncVectorEnv(fns, context="spawn")):
        obs, _ = vec.reset(seed=0)
        assert obs.shape[0] == 2
        obs, rew, term, trunc, _ = vec.step(np.zeros((2, 2), dtype=np.float32))
        assert obs.shape == (2, *vec.single_observation_space.shape) and rew.shape == (2,)
        vec.close()


def test_sb3_subproc_vec_env_steps():
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import SubprocVecEnv

    vec = make_vec_env(
        "lrp_gym:LRPRadarNavFast-v0",
        n_envs=2,
        vec_env_cls=SubprocVecEnv,
        vec_env_kwargs={"start_method": "forkserver"},
    )
    obs = vec.reset()
    obs, rew, done, infos = vec.step(np.zeros((2, 2), dtype=np.float32))
    assert obs.shape[0] == 2 and len(infos) == 2
    vec.close()


def test_unknown_observation_type_is_a_clear_error():
    with pytest.raises(ValueError, match="env.observation.type"):
        LRPRadarNavEnv(observation="lidar")
