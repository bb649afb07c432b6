"""The training workflow never loses work and always stops: overwrite rules, end-of-run
checkpoint and evaluation, resume, the rounded target, and Ctrl-C / SIGTERM on a real run."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from agents.ppo import list_checkpoints, load_hyperparams, train

ENV = "LRPRadarNavFast-v0"


def config(tmp_path, n_envs=1, vec_env="dummy"):
    hp = {
        "n_envs": n_envs,
        "n_timesteps": 1000,
        "policy": "MlpPolicy",
        "normalize": "dict(norm_obs=True, norm_reward=True)",
        "n_steps": 64,
        "batch_size": 64,
        "n_epochs": 1,
        "policy_kwargs": "dict(net_arch=[8], activation_fn=nn.Tanh)",
    }
    # Evaluation and checkpoint intervals far beyond the run: the end of the run must do both.
    lrp = {"vec_env": vec_env, "eval_freq": 10**6, "n_eval_episodes": 1, "checkpoint_freq": 10**6}
    path = tmp_path / "ppo.yaml"
    path.write_text(yaml.safe_dump({ENV: hp, "lrp-gym": {ENV: lrp}}))
    return path


def test_short_run_ends_with_checkpoint_and_evaluation_then_resume_and_force(tmp_path):
    cfg, run, messages = config(tmp_path), tmp_path / "run", []
    info = train(cfg, timesteps=100, out=run, progress_bar=False, log=messages.append)
    assert info["status"] == "done"
    assert info["target_timesteps"] == info["timesteps"] == 128  # two rollouts of 64 steps
    assert any("100 rounded up to 128" in m for m in messages), messages
    assert [s for s, _ in list_checkpoints(run)] == [128]
    assert (run / "checkpoints" / "rl_model_vecnormalize_128_steps.json").is_file()
    assert (run / "best" / "best_model.zip").is_file()
    assert (run / "best" / "vecnormalize.json").is_file()
    assert info["last_eval"]["timesteps"] == 128 and np.isfinite(info["last_eval"]["mean_reward"])
    saved = json.loads((run / "run_info.json").read_text())
    assert saved["target_timesteps"] == saved["timesteps"] == 128
    assert (run / "learning_curve.png").is_file()
    assert str(run / "final" / "model.zip") in info["files"]

    # A finished run is not overwritten by accident.
    first = (run / "final" / "model.zip").read_bytes()
    (run / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="^out: .* holds a finished run of 128 steps.*force"):
        train(cfg, timesteps=64, out=run, progress_bar=False)
    assert (run / "final" / "model.zip").read_bytes() == first
    with pytest.raises(ValueError, match="^force: cannot be combined with resume"):
        train(cfg, timesteps=64, out=run, resume=True, force=True, progress_bar=False)

    # --resume extends it; the learning curve continues.
    with pytest.raises(ValueError, match="^timesteps: the run already has 128 steps"):
        train(cfg, timesteps=128, out=run, resume=True, progress_bar=False)
    info = train(cfg, timesteps=192, out=run, resume=True, progress_bar=False)
    assert info["resumed_from"] == 128 and info["timesteps"] == info["target_timesteps"] == 192
    with np.load(run / "eval" / "evaluations.npz") as d:
        assert list(d["timesteps"]) == [128, 192]
    # ... but never without the normalisation statistics.
    (run / "checkpoints" / "rl_model_vecnormalize_192_steps.json").unlink()
    with pytest.raises(ValueError, match="^resume: .*192_steps.zip has no normalisation"):
        train(cfg, timesteps=256, out=run, resume=True, progress_bar=False)

    # --force starts over and removes only what a run writes.
    info = train(cfg, timesteps=64, out=run, seed=1, force=True, progress_bar=False)
    assert info["status"] == "done" and [s for s, _ in list_checkpoints(run)] == [64]
    assert (run / "notes.txt").read_text() == "mine"


def test_default_config_is_found_from_any_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    env_id, raw = load_hyperparams()
    assert env_id == ENV and raw["n_envs"] >= 1
    with pytest.raises(ValueError, match="^env_id: .* has no section 'Nope-v0'"):
        load_hyperparams(None, "Nope-v0")


# --------------------------------------------------------------------------- signals
def _session_processes(sid: int) -> list[int]:
    """Pids of live processes in session ``sid`` (the run, its forkserver and its workers)."""
    pids = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == sid and fields[0] != "Z":
            pids.append(int(stat.parent.name))
    return pids


def _interrupt(tmp_path, name, send) -> tuple[int, float, str]:
    """Start a long subprocess run, signal it once it trains; (exit code, seconds, stderr)."""
    run = tmp_path / name
    argv = [
        sys.executable,
        "-m",
        "lrp_gym.cli",
        "train",
        "--config",
        str(config(tmp_path, 2, "subproc")),
    ]
    argv += ["--out", str(run), "--timesteps", "1000000", "--no-progress"]
    proc = subprocess.Popen(
        argv,
        cwd=tmp_path,
        start_new_session=True,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120
    while not (run / "run_info.json").is_file() and proc.poll() is None:
        assert time.monotonic() < deadline, "the run did not start"
        time.sleep(0.2)
    time.sleep(1.0)  # inside learn(), workers stepping
    t0 = time.monotonic()
    send(proc.pid)
    out, err = proc.communicate(timeout=60)
    elapsed = time.monotonic() - t0
    for _ in range(50):  # the forkserver leaves shortly after the main process
        if not _session_processes(proc.pid):
            break
        time.sleep(0.1)
    assert not _session_processes(proc.pid), "a worker outlived the run"
    return proc.returncode, elapsed, out + err


@pytest.mark.integration
@pytest.mark.timeout(400)
def test_ctrl_c_and_sigterm_save_a_checkpoint_stop_the_workers_and_resume(tmp_path):
    # Ctrl-C in a terminal: SIGINT to the whole process group.
    code, elapsed, text = _interrupt(tmp_path, "int", lambda pid: os.killpg(pid, signal.SIGINT))
    assert code == 130 and elapsed < 30, (code, elapsed, text)
    assert "saved checkpoint" in text and "resume with: lrp-gym train" in text, text
    assert "Traceback" not in text and "Aborted" not in text
    # `kill PID`: SIGTERM to the main process only.
    code, elapsed, text = _interrupt(tmp_path, "term", lambda pid: os.kill(pid, signal.SIGTERM))
    assert code == 130 and elapsed < 30, (code, elapsed, text)
    steps, ckpt = list_checkpoints(tmp_path / "term")[0]
    assert (ckpt.parent / f"rl_model_vecnormalize_{steps}_steps.json").is_file()
    info = json.loads((tmp_path / "term" / "run_info.json").read_text())
    assert info["status"] == "interrupted" and info["timesteps"] == steps
    # The run continues from its checkpoint.
    cfg = config(tmp_path, 2, "subproc")
    done = train(cfg, timesteps=steps + 1, out=tmp_path / "term", resume=True, progress_bar=False)
    assert done["status"] == "done" and done["resumed_from"] == steps
    assert done["timesteps"] == done["target_timesteps"] == steps + 128


def test_training_on_the_batched_env_runs_and_resumes(tmp_path):
    """``vec_env: batch``: the n_envs robots in one NavBatch (lrp_gym.envs.sb3)."""
    cfg, run = config(tmp_path, n_envs=2, vec_env="batch"), tmp_path / "run"
    info = train(cfg, timesteps=128, out=run, progress_bar=False)
    assert info["status"] == "done" and info["timesteps"] == 128  # one rollout of 64 x 2
    assert [s for s, _ in list_checkpoints(run)] == [128]
    info = train(cfg, timesteps=256, out=run, resume=True, progress_bar=False)
    assert info["resumed_from"] == 128 and info["timesteps"] == 256
    assert np.isfinite(info["last_eval"]["mean_reward"])
