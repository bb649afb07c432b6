"""PPO: zoo-style config parsing, a smoke run that saves and reloads, resume, shipped model."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

from agents.ppo import export_model, list_checkpoints, load_hyperparams, split_hyperparams, train
from agents.registry import DEFAULT_MODEL, load_ppo, make_agent
from lrp_gym.errors import InputError
from lrp_gym.experiments.episodes import make_eval_env
from lrp_gym.experiments.episodes import run_episodes as evaluate

ENV = "LRPRadarNavFast-v0"


def tiny_config(tmp_path, n_envs=1, **extra):
    hp = {
        "n_envs": n_envs,
        "n_timesteps": 1024,
        "policy": "MlpPolicy",
        "normalize": "dict(norm_obs=True, norm_reward=True)",
        "n_steps": 128,
        "batch_size": 64,
        "n_epochs": 2,
        "learning_rate": "lin_3e-4",
        "policy_kwargs": "dict(net_arch=[16, 16], activation_fn=nn.Tanh)",
        **extra,
    }
    lrp = {"vec_env": "dummy", "eval_freq": 256, "n_eval_episodes": 1, "checkpoint_freq": 256}
    path = tmp_path / "ppo.yaml"
    path.write_text(yaml.safe_dump({ENV: hp, "lrp-gym": {ENV: lrp}}))
    return path


def test_split_hyperparams_follows_zoo_conventions(tmp_path):
    env_id, raw = load_hyperparams(tiny_config(tmp_path))
    hp = split_hyperparams(raw)
    assert env_id == ENV and hp["n_envs"] == 1 and hp["n_timesteps"] == 1024
    assert hp["eval_freq"] == 256 and hp["vec_env"] == "dummy"  # from the lrp-gym block
    assert hp["normalize"] == {"norm_obs": True, "norm_reward": True}
    lr = hp["ppo"]["learning_rate"]
    assert lr(1.0) == pytest.approx(3e-4) and lr(0.5) == pytest.approx(1.5e-4)
    import torch

    assert hp["ppo"]["policy_kwargs"]["activation_fn"] is torch.nn.Tanh
    assert not set(hp["ppo"]) & {"vec_env", "eval_freq", "n_envs", "normalize", "env_kwargs"}


def test_config_errors(tmp_path):
    with pytest.raises(ValueError, match="^config: no such file"):
        load_hyperparams(tmp_path / "nope.yaml")
    with pytest.raises(InputError, match="no section"):
        load_hyperparams(tiny_config(tmp_path), "LRPRadarNav-v0")
    with pytest.raises(InputError, match="policy_kwargs"):
        split_hyperparams({"policy_kwargs": "dict(net_arch=[64"})


def test_committed_config_parses():
    env_id, raw = load_hyperparams("configs/ppo.yaml")
    hp = split_hyperparams(raw)
    assert env_id == ENV and hp["vec_env"] == "batch" and hp["eval_freq"] == 20000
    assert hp["ppo"]["batch_size"] <= hp["ppo"]["n_steps"] * hp["n_envs"]
    # rl_zoo3 passes every key of the env's section to PPO: no lrp-gym key may be there.
    sections = yaml.safe_load(open("configs/ppo.yaml"))
    zoo_keys = {"n_envs", "n_timesteps", "policy", "normalize", "policy_kwargs", "env_kwargs"}
    import inspect

    from stable_baselines3 import PPO

    ppo_args = set(inspect.signature(PPO.__init__).parameters)
    for env_id in (k for k in sections if k != "lrp-gym"):
        assert set(sections[env_id]) <= zoo_keys | ppo_args, env_id


def test_smoke_train_save_reload_evaluate_and_resume(tmp_path):
    cfg = tiny_config(tmp_path)
    run = tmp_path / "run"
    info = train(cfg, timesteps=512, out=run, seed=3, progress_bar=False)
    assert info["status"] == "done" and info["timesteps"] == 512
    assert [s for s, _ in list_checkpoints(run)] == [512, 256]
    for f in (
        "final/model.zip",
        "final/vecnormalize.json",
        "best/best_model.zip",
        "best/vecnormalize.json",
        "eval/evaluations.npz",
        "checkpoints/rl_model_vecnormalize_512_steps.json",
        "checkpoints/rl_model_vecnormalize_256_steps.json",
    ):
        assert (run / f).is_file(), f
    assert not list(run.rglob("*.pkl"))  # no pickles: loading them would run code

    # Reload with the saved normalisation statistics; they are the training ones, frozen.
    policy = load_ppo(run / "final" / "model.zip")
    assert policy.obs_normalizer is not None and not policy.obs_normalizer.training
    assert policy.obs_normalizer.obs_rms.count > 500
    env = make_eval_env("ppo", ENV)
    s = evaluate(policy, env, 1, seed=0)
    assert s["episodes"] == 1 and s["mean_steps"] >= 1

    # Resume: the timestep count and the learning curve continue.
    with pytest.raises(InputError, match="holds a finished run of 512 steps"):
        train(cfg, timesteps=1024, out=run, seed=3, progress_bar=False)
    info2 = train(cfg, timesteps=1024, out=run, resume=True, seed=3, progress_bar=False)
    assert info2["resumed_from"] == 512 and info2["timesteps"] == 1024
    assert [s for s, _ in list_checkpoints(run)][0] == 1024
    with np.load(run / "eval" / "evaluations.npz") as d:
        t = d["timesteps"]
    assert t[0] == 256 and t[-1] == 1024 and np.all(np.diff(t) > 0)
    run_info = json.loads((run / "run_info.json").read_text())
    assert run_info["wall_time_s"] >= info["wall_time_s"]
    assert (run / "learning_curve.png").is_file()

    # Shipping copies model + stats and records the run and a final evaluation.
    doc = export_model(run, tmp_path / "models", eval_env_id=ENV, episodes=1, which="final")
    assert (tmp_path / "models" / "ppo_lrp_nav.zip").is_file()
    assert (tmp_path / "models" / "vecnormalize.json").is_file()
    saved = json.loads((tmp_path / "models" / "ppo_lrp_nav.json").read_text())
    assert saved["timesteps"] == 1024 and saved["final_eval"]["episodes"] == 1
    assert doc["final_eval"]["env_id"] == ENV


def test_resume_without_checkpoint_is_input_error(tmp_path):
    with pytest.raises(ValueError, match="^resume: no checkpoint"):
        train(tiny_config(tmp_path), out=tmp_path / "empty", resume=True, progress_bar=False)


def test_subproc_workers_register_env(tmp_path):
    """Forkserver/spawn workers import lrp_gym through the 'lrp_gym:' id prefix."""
    from agents.ppo import make_venv

    venv = make_venv(ENV, 2, 0, {}, "subproc")
    try:
        obs = venv.reset()
        assert obs.shape[0] == 2
        assert not np.allclose(obs[0], obs[1])  # seeds seed + rank differ
    finally:
        venv.close()


def test_shipped_model_reaches_goal():
    """Skips only while agents/models/ has no model; once committed it must pass."""
    if not DEFAULT_MODEL.is_file():
        pytest.skip("no shipped PPO model in agents/models/ yet")
    env = make_eval_env("ppo", ENV)
    s = evaluate(make_agent("ppo", env), env, 2, seed=100)
    assert s["success_rate"] == 1.0, s["per_episode"]
