"""PPO training on the LRP radar navigation env, configured like rl-baselines3-zoo.

``configs/ppo.yaml`` maps an env id to its hyperparameters in the zoo's format (``n_envs``,
``n_timesteps``, ``policy``, ``normalize``, ``policy_kwargs`` as a Python-expression string,
``lin_<x>`` linear schedules, ``env_kwargs``). A few lrp-gym keys are read and removed before
the rest goes to :class:`stable_baselines3.PPO`: ``vec_env`` (``subproc`` or ``dummy``),
``eval_env_id``, ``eval_freq``, ``n_eval_episodes``, ``checkpoint_freq`` (all in total env
steps).

A run directory holds::

    checkpoints/rl_model_<n>_steps.zip + rl_model_vecnormalize_<n>_steps.pkl
    best/best_model.zip + best/vecnormalize.pkl       (EvalCallback's best, with its stats)
    final/model.zip + final/vecnormalize.pkl
    eval/evaluations.npz                              (the learning curve)
    tb/                                               (TensorBoard)
    run_info.json                                     (command, config, timesteps, wall time)

``resume=True`` continues from the newest readable checkpoint: model, VecNormalize statistics,
timestep count and the learning curve so far.
"""

from __future__ import annotations

import json
import re
import shlex
import signal
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from lrp_gym.errors import InputError

DEFAULT_CONFIG = Path("configs/ppo.yaml")
DEFAULT_ENV_ID = "LRPRadarNavFast-v0"
EXTRA_KEYS = ("vec_env", "eval_env_id", "eval_freq", "n_eval_episodes", "checkpoint_freq")
_CKPT = re.compile(r"rl_model_(\d+)_steps\.zip$")


# --------------------------------------------------------------------------- config
def load_hyperparams(path: str | Path, env_id: str | None = None) -> tuple[str, dict[str, Any]]:
    """The hyperparameters of ``env_id`` (default: the first section) from a zoo-style YAML.

    Raises
    ------
    InputError
        Missing, unreadable or non-UTF-8 file, invalid YAML, no section for ``env_id``, or a
        section that is not a mapping.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"--config: no such file: {path}")
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError as exc:
        raise InputError(f"--config: {path} is not UTF-8 text: {exc.reason}") from None
    except OSError as exc:
        raise InputError(f"--config: cannot read {path}: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        raise InputError(f"--config: {path} is not valid YAML: {exc}") from None
    if not isinstance(data, dict) or not data:
        raise InputError(f"--config: {path} must map env ids to hyperparameters")
    env_id = env_id or next(iter(data))
    if env_id not in data:
        raise InputError(
            f"--env: {path} has no section {env_id!r}; sections: {', '.join(map(str, data))}"
        )
    section = data[env_id]
    if not isinstance(section, dict):
        raise InputError(
            f"--config: section {env_id!r} of {path} must be a mapping of hyperparameters, "
            f"got {type(section).__name__}"
        )
    return str(env_id), dict(section)


def _schedule(value: Any) -> Any:
    """Zoo's ``lin_<x>``: linear decay from x to 0 over training (else the value as is)."""
    if isinstance(value, str) and value.startswith("lin_"):
        start = float(value[4:])
        return lambda progress_remaining: progress_remaining * start
    return float(value) if isinstance(value, str) else value


def _eval_expr(text: str, what: str) -> Any:
    """Evaluate a zoo-style Python expression (``dict(net_arch=[64, 64], activation_fn=nn.Tanh)``)."""
    from torch import nn

    try:
        return eval(
            text, {"__builtins__": {}}, {"dict": dict, "nn": nn, "True": True, "False": False}
        )  # noqa: S307
    except Exception as exc:
        raise InputError(f"--config: cannot parse {what} {text!r}: {exc}") from None


def split_hyperparams(hp: dict[str, Any]) -> dict[str, Any]:
    """Split a zoo section into the parts the trainer needs (values converted).

    Returns
    -------
    dict
        ``n_envs``, ``n_timesteps``, ``policy``, ``normalize`` (kwargs for VecNormalize or
        None), ``env_kwargs``, the lrp-gym extras, and ``ppo`` (kwargs for PPO).
    """
    hp = dict(hp)
    try:
        n_envs = int(hp.pop("n_envs", 1))
        n_timesteps = int(float(hp.pop("n_timesteps", 1e5)))
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(f"--config: n_envs / n_timesteps must be numbers: {exc}") from None
    out: dict[str, Any] = {
        "n_envs": n_envs,
        "n_timesteps": n_timesteps,
        "policy": hp.pop("policy", "MlpPolicy"),
        "env_kwargs": dict(hp.pop("env_kwargs", None) or {}),
    }
    norm = hp.pop("normalize", False)
    if isinstance(norm, str):
        norm = _eval_expr(norm, "normalize")
    out["normalize"] = (dict(norm) if isinstance(norm, dict) else {}) if norm else None
    for key in EXTRA_KEYS:
        out[key] = hp.pop(key, None)
    for key in ("learning_rate", "clip_range"):
        if key in hp:
            hp[key] = _schedule(hp[key])
    if isinstance(hp.get("policy_kwargs"), str):
        hp["policy_kwargs"] = _eval_expr(hp["policy_kwargs"], "policy_kwargs")
    out["ppo"] = hp
    return out


# --------------------------------------------------------------------------- envs
def gym_id(env_id: str) -> str:
    """``lrp_gym:<id>``: spawn/forkserver workers import lrp_gym and so register the id."""
    return env_id if ":" in env_id else f"lrp_gym:{env_id}"


def make_venv(
    env_id: str,
    n_envs: int,
    seed: int,
    env_kwargs: dict[str, Any],
    vec_env: str = "dummy",
    monitor_dir: str | None = None,
):
    """A Monitor-wrapped vectorised env (``vec_env``: ``subproc`` or ``dummy``)."""
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    if vec_env not in ("subproc", "dummy"):
        raise InputError(f"--config: vec_env must be 'subproc' or 'dummy', got {vec_env!r}")
    cls = SubprocVecEnv if (vec_env == "subproc" and n_envs > 1) else DummyVecEnv
    return make_vec_env(
        gym_id(env_id),
        n_envs=n_envs,
        seed=seed,
        env_kwargs=env_kwargs,
        vec_env_cls=cls,
        monitor_dir=monitor_dir,
    )


# --------------------------------------------------------------------------- checkpoints
def list_checkpoints(run_dir: str | Path) -> list[tuple[int, Path]]:
    """(timesteps, path) of every checkpoint in ``run_dir/checkpoints``, newest first."""
    ckpt_dir = Path(run_dir) / "checkpoints"
    found = []
    for p in ckpt_dir.glob("rl_model_*_steps.zip"):
        m = _CKPT.search(p.name)
        if m:
            found.append((int(m.group(1)), p))
    return sorted(found, reverse=True)


def _save_pair(model, zip_path: Path) -> None:
    """Save model and its VecNormalize stats (``vecnormalize.pkl`` alongside) atomically."""
    zip_path.parent.mkdir(parents=True, exist_ok=True)
    tmp = zip_path.with_name(zip_path.stem + ".tmp.zip")
    model.save(tmp)
    tmp.replace(zip_path)
    vn = model.get_vec_normalize_env()
    if vn is not None:
        pkl = zip_path.with_name("vecnormalize.pkl")
        tmp_pkl = pkl.with_name("vecnormalize.tmp.pkl")
        vn.save(tmp_pkl)
        tmp_pkl.replace(pkl)


def _callbacks(run_dir: Path, eval_env, eval_freq: int, n_eval: int, ckpt_freq: int, n_envs: int):
    from stable_baselines3.common.callbacks import BaseCallback, CheckpointCallback, EvalCallback

    class SaveVecNormalizeCallback(BaseCallback):
        """Save the VecNormalize statistics next to EvalCallback's new best model."""

        def _on_step(self) -> bool:
            vn = self.model.get_vec_normalize_env()
            if vn is not None:
                vn.save(str(run_dir / "best" / "vecnormalize.pkl"))
            return True

    checkpoint = CheckpointCallback(
        save_freq=max(ckpt_freq // n_envs, 1),
        save_path=str(run_dir / "checkpoints"),
        name_prefix="rl_model",
        save_vecnormalize=True,
    )
    evaluation = EvalCallback(
        eval_env,
        callback_on_new_best=SaveVecNormalizeCallback(),
        n_eval_episodes=n_eval,
        eval_freq=max(eval_freq // n_envs, 1),
        log_path=str(run_dir / "eval"),
        best_model_save_path=str(run_dir / "best"),
        deterministic=True,
        verbose=0,
    )
    return checkpoint, evaluation


def _restore_curve(evaluation, run_dir: Path) -> None:
    """Continue the learning curve of an interrupted run instead of overwriting it."""
    npz = run_dir / "eval" / "evaluations.npz"
    if not npz.is_file():
        return
    with np.load(npz) as d:
        evaluation.evaluations_timesteps = [int(t) for t in d["timesteps"]]
        evaluation.evaluations_results = [list(r) for r in d["results"]]
        evaluation.evaluations_length = [list(r) for r in d["ep_lengths"]]
        if "successes" in d:
            evaluation.evaluations_successes = [list(r) for r in d["successes"]]
        if len(d["results"]):
            evaluation.best_mean_reward = float(np.max(np.mean(d["results"], axis=1)))


# --------------------------------------------------------------------------- training
def train(
    config: str | Path = DEFAULT_CONFIG,
    env_id: str | None = None,
    timesteps: int | None = None,
    out: str | Path | None = None,
    resume: bool = False,
    seed: int = 0,
    progress_bar: bool = True,
    verbose: int = 0,
) -> dict[str, Any]:
    """Train PPO from a zoo-style config; returns the run info (also in ``run_info.json``).

    Parameters
    ----------
    config : path
        Zoo-style hyperparameter YAML.
    env_id : str, optional
        Section (and env) to train; default: the file's first section.
    timesteps : int, optional
        Total env steps (overrides ``n_timesteps``); with ``resume`` the run stops there too.
    out : path, optional
        Run directory; default ``runs/ppo-<env_id>-s<seed>``.
    resume : bool
        Continue from the newest checkpoint in ``out``.
    seed : int
        Seeds torch, numpy, the training envs (``seed + rank``) and the eval env.
    """
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.utils import set_random_seed
    from stable_baselines3.common.vec_env import VecNormalize

    command = shlex.join([Path(sys.argv[0]).name, *sys.argv[1:]])
    env_id, raw = load_hyperparams(config, env_id)
    hp = split_hyperparams(raw)
    total = int(timesteps) if timesteps is not None else hp["n_timesteps"]
    if total < 1:
        raise InputError(f"--timesteps: must be at least 1, got {total}")
    run_dir = Path(out) if out is not None else Path("runs") / f"ppo-{env_id}-s{seed}"
    checkpoints = list_checkpoints(run_dir)
    if resume and not checkpoints:
        raise InputError(f"--resume: no checkpoint in {run_dir / 'checkpoints'}")
    if not resume and checkpoints:
        raise InputError(
            f"--out: {run_dir} already holds checkpoints; pass --resume or another --out"
        )
    run_dir.mkdir(parents=True, exist_ok=True)

    # Small MLPs: one thread avoids oversubscribing the cores the env workers need.
    torch.set_num_threads(1)
    set_random_seed(seed)
    n_envs = hp["n_envs"]
    vec_env = hp["vec_env"] or "dummy"
    venv = make_venv(env_id, n_envs, seed, hp["env_kwargs"], vec_env)
    eval_id = hp["eval_env_id"] or env_id
    eval_venv = make_venv(eval_id, 1, seed + 10_000, hp["env_kwargs"], "dummy")

    previous_wall = 0.0
    if resume:
        model, venv, start = _load_checkpoint(checkpoints, venv, run_dir)
        info_path = run_dir / "run_info.json"
        if info_path.is_file():
            previous_wall = float(json.loads(info_path.read_text()).get("wall_time_s", 0.0))
    else:
        if hp["normalize"] is not None:
            venv = VecNormalize(venv, gamma=hp["ppo"].get("gamma", 0.99), **hp["normalize"])
        model = PPO(
            hp["policy"],
            venv,
            seed=seed,
            verbose=verbose,
            tensorboard_log=str(run_dir / "tb"),
            device="cpu",
            **hp["ppo"],
        )
        start = 0
    if hp["normalize"] is not None:
        eval_venv = VecNormalize(
            eval_venv,
            training=False,
            norm_reward=False,
            **{k: v for k, v in hp["normalize"].items() if k not in ("norm_reward", "training")},
        )

    n_eval = int(hp["n_eval_episodes"] or 10)
    eval_freq = int(float(hp["eval_freq"] or 10_000))
    ckpt_freq = int(float(hp["checkpoint_freq"] or 10_000))
    checkpoint, evaluation = _callbacks(run_dir, eval_venv, eval_freq, n_eval, ckpt_freq, n_envs)
    if resume:
        _restore_curve(evaluation, run_dir)

    info: dict[str, Any] = {
        "command": command,
        "config": str(config),
        "env_id": env_id,
        "eval_env_id": eval_id,
        "seed": seed,
        "n_envs": n_envs,
        "vec_env": vec_env,
        "hyperparams": raw,
        "target_timesteps": total,
        "resumed_from": start if resume else None,
        "status": "running",
    }
    _write_json(run_dir / "run_info.json", {**info, "wall_time_s": previous_wall})
    t0 = time.perf_counter()
    status = "failed"
    previous_term = _term_as_interrupt()
    try:
        remaining = total - model.num_timesteps
        if remaining > 0:
            model.learn(
                remaining,
                callback=[checkpoint, evaluation],
                progress_bar=progress_bar,
                reset_num_timesteps=not resume,
                tb_log_name="PPO",
            )
        status = "done"
    except KeyboardInterrupt:
        # Keep what was learned: a checkpoint at the current count, then stop.
        status = "interrupted"
        model.save(run_dir / "checkpoints" / f"rl_model_{model.num_timesteps}_steps.zip")
        vn = model.get_vec_normalize_env()
        if vn is not None:
            vn.save(
                str(
                    run_dir
                    / "checkpoints"
                    / f"rl_model_vecnormalize_{model.num_timesteps}_steps.pkl"
                )
            )
        raise
    finally:
        if previous_term is not None:
            signal.signal(signal.SIGTERM, previous_term)
        wall = previous_wall + time.perf_counter() - t0
        if status == "done":
            _save_pair(model, run_dir / "final" / "model.zip")
        last = _last_eval(evaluation)
        info.update(
            status=status,
            timesteps=int(model.num_timesteps),
            wall_time_s=round(wall, 1),
            last_eval=last,
            best_mean_reward=float(evaluation.best_mean_reward),
        )
        _write_json(run_dir / "run_info.json", info)
        venv.close()
        eval_venv.close()
        if evaluation.evaluations_timesteps:
            plot_learning_curve(run_dir, run_dir / "learning_curve.png", f"PPO on {env_id}")
    return info


def _term_as_interrupt():
    """Treat SIGTERM (``kill PID``) like Ctrl-C so a stopped run still writes a checkpoint."""

    def handler(signum, frame):
        raise KeyboardInterrupt

    try:
        return signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread
        return None


def _load_checkpoint(checkpoints, venv, run_dir: Path):
    """Newest readable checkpoint (a half-written one is skipped) with its VecNormalize stats."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    errors = []
    for steps, path in checkpoints:
        vn_path = path.with_name(f"rl_model_vecnormalize_{steps}_steps.pkl")
        try:
            env = VecNormalize.load(str(vn_path), venv) if vn_path.is_file() else venv
            model = PPO.load(path, env=env, device="cpu", tensorboard_log=str(run_dir / "tb"))
        except Exception as exc:  # a checkpoint cut short by the interruption
            errors.append(f"{path.name}: {exc}")
            continue
        return model, env, steps
    raise InputError(f"--resume: no readable checkpoint in {run_dir}: {'; '.join(errors)}")


def _last_eval(evaluation) -> dict[str, Any] | None:
    if not evaluation.evaluations_timesteps:
        return None
    res = np.asarray(evaluation.evaluations_results[-1], dtype=float)
    out = {
        "timesteps": int(evaluation.evaluations_timesteps[-1]),
        "mean_reward": float(res.mean()),
        "mean_ep_length": float(np.mean(evaluation.evaluations_length[-1])),
    }
    if evaluation.evaluations_successes:
        out["success_rate"] = float(np.mean(evaluation.evaluations_successes[-1]))
    return out


def _write_json(path: Path, data: dict[str, Any]) -> None:
    from lrp_gym.commands._common import write_json

    write_json(data, path)


# --------------------------------------------------------------------------- curve + export
def plot_learning_curve(run_dir: str | Path, out_png: str | Path, title: str = "PPO") -> Path:
    """Mean eval return and success rate against timesteps from ``eval/evaluations.npz``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from lrp_gym.commands._common import save_figure

    npz = Path(run_dir) / "eval" / "evaluations.npz"
    if not npz.is_file():
        raise InputError(f"no learning curve: {npz} is missing")
    with np.load(npz) as d:
        t, res = d["timesteps"], d["results"]
        succ = d["successes"] if "successes" in d and d["successes"].size else None
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    mean, std = res.mean(axis=1), res.std(axis=1)
    ax.plot(t, mean, color="C0", label="mean eval return")
    ax.fill_between(t, mean - std, mean + std, color="C0", alpha=0.2)
    ax.set_xlabel("timesteps")
    ax.set_ylabel("return", color="C0")
    if succ is not None:
        ax2 = ax.twinx()
        ax2.plot(t, 100 * succ.mean(axis=1), color="C1", label="success rate")
        ax2.set_ylabel("success rate [%]", color="C1")
        ax2.set_ylim(-5, 105)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    return save_figure(fig, out_png)


def export_model(
    run_dir: str | Path,
    dest_dir: str | Path,
    name: str = "ppo_lrp_nav",
    which: str = "best",
    eval_env_id: str = "LRPRadarNav-v0",
    episodes: int = 50,
    seed: int = 1000,
) -> dict[str, Any]:
    """Ship a run's model: ``<name>.zip`` + ``vecnormalize.pkl`` + ``<name>.json``.

    The JSON holds the run info (command, timesteps, wall time) and a final evaluation of the
    exported model on ``eval_env_id`` (goal episodes on seeds ``seed, seed + 1, ...``).

    Parameters
    ----------
    which : {"best", "final"}
        EvalCallback's best model or the model at the end of training.
    """
    import shutil

    from agents.evaluate import evaluate, find_vecnormalize, load_ppo, make_eval_env, public

    run_dir, dest = Path(run_dir), Path(dest_dir)
    src = run_dir / ("best/best_model.zip" if which == "best" else "final/model.zip")
    if not src.is_file():
        raise InputError(f"--export: {src} does not exist (has the run finished?)")
    vn = find_vecnormalize(src)
    dest.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(src, dest / f"{name}.zip")
    if vn is not None:
        shutil.copyfile(vn, dest / "vecnormalize.pkl")
    env = make_eval_env("ppo", eval_env_id)
    t0 = time.perf_counter()
    summary = public(evaluate(load_ppo(dest / f"{name}.zip"), env, episodes, seed))
    env.close()
    summary.pop("per_episode", None)
    info_path = run_dir / "run_info.json"
    run_info = json.loads(info_path.read_text()) if info_path.is_file() else {}
    doc = {
        "model": f"{name}.zip",
        "source": str(src),
        "train_command": run_info.get("command"),
        "config": run_info.get("config"),
        "env_id": run_info.get("env_id"),
        "seed": run_info.get("seed"),
        "timesteps": run_info.get("timesteps"),
        "wall_time_s": run_info.get("wall_time_s"),
        "hyperparams": run_info.get("hyperparams"),
        "final_eval": {
            "env_id": eval_env_id,
            "episodes": episodes,
            "seed": seed,
            "eval_wall_time_s": round(time.perf_counter() - t0, 1),
            **summary,
        },
    }
    _write_json(dest / f"{name}.json", doc)
    return doc
