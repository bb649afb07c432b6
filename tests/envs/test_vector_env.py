"""The batched env: robot i of a batch is, bit for bit, the single env seeded seed + i."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import lrp_gym  # noqa: F401  (registers the envs)
from lrp_gym.envs.vector_env import LRPRadarNavVectorEnv

ENV_ID = "LRPRadarNavFast-v0"
# Short episodes so that every robot ends (and autoresets) several times in a short test.
SHORT = {"task": {"max_episode_steps": 5}}


def _actions(rng: np.random.Generator, n: int) -> np.ndarray:
    a = rng.uniform(-1.0, 1.0, (n, 2)).astype(np.float32)
    a[:, 0] = np.abs(a[:, 0])  # mostly forward: some episodes end in a collision
    return a


def _assert_info_equal(vector_info: dict, i: int, info: dict) -> None:
    for key, value in info.items():
        if isinstance(value, dict):
            _assert_info_equal(vector_info[key], i, value)
            continue
        assert vector_info[f"_{key}"][i], key
        np.testing.assert_array_equal(vector_info[key][i], value, err_msg=key)


def _compare_with_single_envs(
    n: int, seed: int, steps: int, max_episode_steps: int | None = None, **make_kwargs
) -> int:
    """Step a batch of ``n`` and ``n`` single envs alike; assert equality; count autoresets.

    ``max_episode_steps`` goes to ``gym.make_vec``; the single envs apply Gymnasium's
    ``TimeLimit`` rule here (truncated once ``max_episode_steps`` steps were taken, even on a
    termination) rather than through ``gym.make``: importing rl_zoo3 (as the zoo tests do)
    swaps ``gym.make``'s ``TimeLimit`` for a patched one with other flags and info keys.
    """
    venv = gym.make_vec(ENV_ID, num_envs=n, max_episode_steps=max_episode_steps, **make_kwargs)
    assert isinstance(venv, LRPRadarNavVectorEnv)
    envs = [gym.make(ENV_ID, **make_kwargs) for _ in range(n)]
    obs, infos = venv.reset(seed=seed)
    for i, env in enumerate(envs):
        o, info = env.reset(seed=seed + i)
        np.testing.assert_array_equal(obs[i], o)
        _assert_info_equal(infos, i, info)
    rng = np.random.default_rng(0)
    ended = np.zeros(n, dtype=bool)  # the single env's episode ended at the last step
    elapsed = np.zeros(n, dtype=int)
    autoresets = 0
    for _ in range(steps):
        actions = _actions(rng, n)
        obs, rewards, terminated, truncated, infos = venv.step(actions)
        for i, env in enumerate(envs):
            if ended[i]:
                # Next-step autoreset: the action is ignored, the next episode's first frame.
                o, info = env.reset()
                r, te, tr = 0.0, False, False
                elapsed[i] = 0
                autoresets += 1
            else:
                o, r, te, tr, info = env.step(actions[i])
                elapsed[i] += 1
                tr = tr or (max_episode_steps is not None and elapsed[i] >= max_episode_steps)
            np.testing.assert_array_equal(obs[i], o)
            assert (rewards[i], terminated[i], truncated[i]) == (r, te, tr)
            _assert_info_equal(infos, i, info)
            ended[i] = te or tr
    return autoresets


@pytest.mark.parametrize("n", [1, 3, 8])
def test_robot_i_is_the_single_env_seeded_seed_plus_i(n):
    autoresets = _compare_with_single_envs(n, 20, 12 if n < 8 else 8, overrides=SHORT)
    assert autoresets >= n  # every robot went through at least one autoreset


def test_max_episode_steps_truncates_as_the_single_envs_time_limit():
    # A limit of 3 on top of the scenario's 5; gym.make_vec passes max_episode_steps to the
    # vector entry point, which must give TimeLimit's flags.
    autoresets = _compare_with_single_envs(2, 3, 9, overrides=SHORT, max_episode_steps=3)
    assert autoresets >= 4
    venv = gym.make_vec(ENV_ID, num_envs=1, max_episode_steps=2)
    venv.reset(seed=0)
    flags = [venv.step(np.zeros((1, 2)))[3][0] for _ in range(2)]
    assert flags == [False, True]  # the robot at rest: only the limit ends the episode
    with pytest.raises(ValueError, match="max_episode_steps"):
        LRPRadarNavVectorEnv(1, max_episode_steps=0)


def test_metadata_spaces_and_info_masks():
    venv = LRPRadarNavVectorEnv(4, radar_fidelity="detections")
    assert venv.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    single = gym.make(ENV_ID)
    assert venv.single_observation_space == single.observation_space
    assert venv.observation_space.shape == (4, *single.observation_space.shape)
    assert venv.action_space.shape == (4, 2)
    obs, infos = venv.reset(seed=0)
    assert venv.observation_space.contains(obs)
    assert infos["_converged"].all() and infos["true_pose"].shape == (4, 3)
    # Distinct seeds: distinct start poses.
    assert len({tuple(p) for p in infos["true_pose"].round(6)}) == 4


def test_partial_reset_and_seed_list():
    venv = LRPRadarNavVectorEnv(3, radar_fidelity="detections")
    _, infos = venv.reset(seed=[5, 6, 7])
    again = LRPRadarNavVectorEnv(3, radar_fidelity="detections")
    _, infos_int = again.reset(seed=5)
    np.testing.assert_array_equal(infos["true_pose"], infos_int["true_pose"])
    venv.step(np.zeros((3, 2)))
    before = venv.core.pose.copy()
    _, part = venv.reset(seed=[None, 6, None], options={"reset_mask": [False, True, False]})
    assert list(part["_true_pose"]) == [False, True, False]
    np.testing.assert_array_equal(part["true_pose"][1], infos["true_pose"][1])
    np.testing.assert_array_equal(venv.core.pose[[0, 2]], before[[0, 2]])
    fresh = LRPRadarNavVectorEnv(2, radar_fidelity="detections")
    with pytest.raises(ValueError, match=r"robots \[1\] were never reset"):
        fresh.reset(seed=0, options={"reset_mask": [True, False]})


def test_bad_actions_name_the_argument():
    venv = LRPRadarNavVectorEnv(2, radar_fidelity="detections")
    venv.reset(seed=0)
    with pytest.raises(ValueError, match=r"actions must have shape \(2, 2\)"):
        venv.step(np.zeros(2))
    with pytest.raises(ValueError, match="actions must be finite"):
        venv.step(np.full((2, 2), np.nan))
    with pytest.raises(ValueError, match="num_envs must be at least 1"):
        LRPRadarNavVectorEnv(0)


def test_step_before_reset_is_refused():
    venv = LRPRadarNavVectorEnv(2, radar_fidelity="detections")
    with pytest.raises(RuntimeError, match=r"call reset\(\) first"):
        venv.step(np.zeros((2, 2)))


def test_render_draws_robot_0():
    venv = LRPRadarNavVectorEnv(2, radar_fidelity="detections", render_mode="rgb_array")
    venv.reset(seed=0)
    frame = venv.render()
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.std() > 0
    venv.close()


def test_dict_observation_batches_per_key():
    venv = LRPRadarNavVectorEnv(2, radar_fidelity="detections", observation="dict")
    obs, _ = venv.reset(seed=0)
    assert venv.observation_space.contains(obs)
    assert obs["pose"].shape[0] == 2


def test_sb3_batch_vecenv_matches_dummy_vecenv_and_learns():
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, VecMonitor, VecNormalize

    from lrp_gym.envs.sb3 import NavBatchVecEnv

    n, kwargs = 3, {"overrides": SHORT}
    batch = NavBatchVecEnv(ENV_ID, n, kwargs)
    dummy = make_vec_env(ENV_ID, n_envs=n, seed=5, vec_env_cls=DummyVecEnv, env_kwargs=kwargs)
    batch.seed(5)
    np.testing.assert_array_equal(batch.reset(), dummy.reset())
    rng = np.random.default_rng(1)
    terminal = 0
    for _ in range(8):
        actions = _actions(rng, n)
        out_b = batch.step(actions)
        out_d = dummy.step(actions)
        for x, y in zip(out_b[:3], out_d[:3], strict=True):
            np.testing.assert_array_equal(x, y)
        for info_b, info_d in zip(out_b[3], out_d[3], strict=True):
            assert info_b["TimeLimit.truncated"] == info_d["TimeLimit.truncated"]
            if "terminal_observation" in info_d:
                terminal += 1
                np.testing.assert_array_equal(
                    info_b["terminal_observation"], info_d["terminal_observation"]
                )
    assert terminal >= n
    # PPO runs a few hundred steps on it (VecMonitor for episode stats, VecNormalize on top).
    venv = VecNormalize(VecMonitor(batch))
    model = PPO("MlpPolicy", venv, n_steps=64, batch_size=64, n_epochs=1, device="cpu")
    model.learn(192)
    assert model.num_timesteps >= 192 and len(model.ep_info_buffer) > 0
