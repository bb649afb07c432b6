"""Model files that do not run code: statistics as JSON, PPO zips loaded without unpickling."""

from __future__ import annotations

import base64
import json
import pickle
import shutil
import zipfile

import gymnasium as gym
import numpy as np
import pytest

from agents import model_io
from agents.registry import DEFAULT_MODEL, MODELS_DIR, load_ppo, make_agent
from lrp_gym.cli import main
from lrp_gym.errors import InputError
from lrp_gym.experiments.episodes import make_eval_env


class _Boom:
    """Unpickling this creates ``marker``: proof that a load ran code from the file."""

    def __init__(self, marker):
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


def _copy_shipped(tmp_path):
    shutil.copy(DEFAULT_MODEL, tmp_path / "model.zip")
    shutil.copy(MODELS_DIR / "vecnormalize.json", tmp_path / "vecnormalize.json")
    return tmp_path / "model.zip"


def _rewrite_data(zip_path, edit):
    """Rewrite the ``data`` JSON entry of a model zip with ``edit(data)``."""
    with zipfile.ZipFile(zip_path) as z:
        entries = {n: z.read(n) for n in z.namelist()}
    data = json.loads(entries["data"])
    edit(data)
    entries["data"] = json.dumps(data).encode()
    with zipfile.ZipFile(zip_path, "w") as z:
        for n, b in entries.items():
            z.writestr(n, b)


def test_shipped_model_has_json_statistics_and_no_pickle():
    assert (MODELS_DIR / "vecnormalize.json").is_file()
    assert not list(MODELS_DIR.glob("*.pkl"))
    doc = model_io.read_stats(MODELS_DIR / "vecnormalize.json")
    env = gym.make("LRPRadarNav-v0")
    assert doc["norm_obs"] and (len(doc["obs_rms"]["mean"]),) == env.observation_space.shape
    env.close()


@pytest.mark.parametrize("env_id", ["LRPRadarNav-v0", "LRPRadarNavFast-v0"])
def test_shipped_model_observation_space_is_the_envs(env_id):
    """Shape and bounds as saved in the zip (read without unpickling) equal the env's space, so
    the shipped model sees the current layout (with the confidence and unimodality)."""
    saved = model_io._box(model_io.read_zip_data(DEFAULT_MODEL)["observation_space"])
    env = gym.make(env_id)
    space = env.observation_space
    env.close()
    assert saved is not None and saved.shape == space.shape == (20,)
    np.testing.assert_allclose(saved.low, space.low, atol=1e-5)
    np.testing.assert_allclose(saved.high, space.high, atol=1e-5)


def test_shipped_model_loads_without_unpickling(monkeypatch):
    import cloudpickle

    def refuse(*args, **kwargs):
        raise AssertionError("something was unpickled")

    monkeypatch.setattr(cloudpickle, "loads", refuse)
    monkeypatch.setattr(pickle, "loads", refuse)
    monkeypatch.setattr(pickle, "load", refuse)
    policy = load_ppo()
    action, _ = policy.predict(np.zeros(20, np.float32))
    assert action.shape == (2,) and np.all(np.abs(action) <= 1.0)


def test_pickled_payload_is_never_run(tmp_path):
    path = _copy_shipped(tmp_path)
    marker = tmp_path / "pwned"
    payload = base64.b64encode(pickle.dumps(_Boom(marker))).decode()

    def poison(data):
        for key in ("lr_schedule", "observation_space", "policy_kwargs", "_last_obs"):
            data[key][":serialized:"] = payload

    _rewrite_data(path, poison)
    load_ppo(path)
    assert not marker.exists()

    _rewrite_data(path, lambda d: d.update(sneaky={":type:": "x", ":serialized:": payload}))
    with pytest.raises(InputError, match="'sneaky' as a pickle"):
        load_ppo(path)
    assert not marker.exists()


def test_statistics_round_trip_exactly(tmp_path):
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    import lrp_gym  # noqa: F401

    venv = VecNormalize(DummyVecEnv([lambda: make_eval_env("ppo", "LRPRadarNavFast-v0")]))
    venv.reset()
    for _ in range(5):
        venv.step(np.zeros((1, 2), np.float32))
    path = model_io.write_stats(venv, tmp_path / "vecnormalize.json")
    doc = model_io.read_stats(path)
    norm = model_io.obs_normalizer(doc)
    obs = np.random.default_rng(0).normal(size=(3, 20)).astype(np.float32)
    venv.training = False
    np.testing.assert_array_equal(norm.normalize_obs(obs), venv.normalize_obs(obs))
    again = model_io.vecnormalize_from_stats(doc, venv.venv)
    np.testing.assert_array_equal(again.obs_rms.var, venv.obs_rms.var)
    assert again.ret_rms.count == venv.ret_rms.count and again.clip_obs == venv.clip_obs
    venv.close()


def test_find_stats_conventions(tmp_path):
    ck = tmp_path / "rl_model_500_steps.zip"
    ck.touch()
    assert model_io.find_stats(ck) is None
    assert model_io.stats_path_for(ck).name == "rl_model_vecnormalize_500_steps.json"
    assert model_io.stats_path_for(tmp_path / "model.zip").name == "vecnormalize.json"
    (tmp_path / "vecnormalize.json").touch()
    assert model_io.find_stats(ck) == tmp_path / "vecnormalize.json"
    (tmp_path / "rl_model_vecnormalize_500_steps.json").touch()
    assert model_io.find_stats(ck) == tmp_path / "rl_model_vecnormalize_500_steps.json"


def test_missing_statistics_is_one_clear_line(tmp_path, capsys):
    path = _copy_shipped(tmp_path)
    (tmp_path / "vecnormalize.json").unlink()
    (tmp_path / "vecnormalize.pkl").write_bytes(b"old pickle")
    with pytest.raises(SystemExit) as exc:
        main(["evaluate", "--agent", "ppo", "--model", str(path), "--episodes", "1"])
    err = " ".join(capsys.readouterr().err.split())  # one message (the console may wrap it)
    assert exc.value.code == 2 and err.startswith("error: --model:") and "Traceback" not in err
    assert "no normalisation statistics" in err and "python -m agents.model_io" in err


def test_model_for_other_spaces_is_refused(tmp_path):
    path = _copy_shipped(tmp_path)

    def other_obs(data):
        data["observation_space"]["_shape"] = [22]

    _rewrite_data(path, other_obs)
    env = make_eval_env("ppo", "LRPRadarNavFast-v0")
    with pytest.raises(InputError, match=r"observations of shape \(22,\), the env has \(20,\)"):
        make_agent("ppo", env, path)

    path = _copy_shipped(tmp_path)
    _rewrite_data(path, lambda d: d["action_space"].update(high="[2. 2.]"))
    with pytest.raises(InputError, match="other action bounds"):
        make_agent("ppo", env, path)
    env.close()


def test_convert_old_pickle(tmp_path):
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    venv = VecNormalize(DummyVecEnv([lambda: make_eval_env("ppo", "LRPRadarNavFast-v0")]))
    venv.reset()
    venv.save(str(tmp_path / "vecnormalize.pkl"))
    assert model_io.main([str(tmp_path / "vecnormalize.pkl")]) == 0
    doc = model_io.read_stats(tmp_path / "vecnormalize.json")
    np.testing.assert_array_equal(doc["obs_rms"]["mean"], venv.obs_rms.mean)
    venv.close()
