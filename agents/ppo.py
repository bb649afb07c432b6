"""PPO training on the LRP radar navigation env, configured like rl-baselines3-zoo.

The config format is described in :mod:`agents.ppo_config`. A run directory holds::

    checkpoints/rl_model_<n>_steps.zip + rl_model_vecnormalize_<n>_steps.json
    best/best_model.zip + best/vecnormalize.json     (EvalCallback's best, with its statistics)
    final/model.zip + final/vecnormalize.json
    eval/evaluations.npz                             (the learning curve)
    tb/                                              (TensorBoard)
    run_info.json                                    (command, config, timesteps, wall time)
    learning_curve.png

Every run ends with a checkpoint, also when stopped by Ctrl-C or SIGTERM, and ``resume=True``
continues (or extends) a run from its newest checkpoint: model, normalisation statistics,
timestep count and learning curve. PPO trains on whole rollouts of ``n_steps * n_envs`` steps,
so the target is rounded up to a whole number of rollouts. Statistics are JSON and models load
without unpickling (:mod:`agents.model_io`).
"""

from __future__ import annotations

import json
import math
import shlex
import shutil
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from agents import checkpoints as ck
from agents.checkpoints import list_checkpoints
from agents.model_io import find_stats, load_ppo_safely, read_stats, save_model, stats_path_for
from agents.model_io import vecnormalize_from_stats as _vn_from_stats
from agents.ppo_config import DEFAULT_CONFIG, load_hyperparams, schedules, split_hyperparams
from agents.training_io import export_model, plot_learning_curve, write_json
from lrp_gym.errors import InputError

__all__ = [
    "DEFAULT_CONFIG",
    "export_model",
    "list_checkpoints",
    "load_hyperparams",
    "make_venv",
    "plot_learning_curve",
    "split_hyperparams",
    "train",
]
RUN_OUTPUTS = ("checkpoints", "best", "final", "eval", "tb", "run_info.json", "learning_curve.png")


# --------------------------------------------------------------------------- envs
#: How ``n_envs`` envs are run (``vec_env`` in the config's lrp-gym section).
VEC_ENVS = ("batch", "subproc", "dummy")


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
) -> Any:
    """A Monitor-wrapped vectorised env (``vec_env``: ``batch``, ``subproc`` or ``dummy``).

    ``batch`` runs the ``n_envs`` robots in one batched env in this process
    (:class:`lrp_gym.envs.sb3.NavBatchVecEnv`); ``subproc`` and ``dummy`` run ``n_envs`` env
    copies in worker processes or in a loop. Subprocess workers ignore SIGINT/SIGTERM: the
    main process stops them (see :func:`agents.checkpoints.close_venv`).
    """
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecMonitor

    if vec_env not in VEC_ENVS:
        raise InputError(f"config: vec_env must be one of {', '.join(VEC_ENVS)}, got {vec_env!r}")
    if vec_env == "batch":
        from lrp_gym.envs.sb3 import NavBatchVecEnv

        batch = NavBatchVecEnv(gym_id(env_id), n_envs, env_kwargs)
        batch.seed(seed)
        return VecMonitor(batch, filename=None if monitor_dir is None else f"{monitor_dir}/batch")
    subproc = vec_env == "subproc" and n_envs > 1
    return make_vec_env(
        gym_id(env_id),
        n_envs=n_envs,
        seed=seed,
        env_kwargs=env_kwargs,
        vec_env_cls=SubprocVecEnv if subproc else DummyVecEnv,
        monitor_dir=monitor_dir,
        wrapper_class=ck.ignore_stop_signals if subproc else None,
    )


# --------------------------------------------------------------------------- run folder
def _prepare_run_dir(run_dir: Path, resume: bool, force: bool) -> list[tuple[int, Path]]:
    """Check the run folder against --resume/--force; with --force clear the old run's outputs."""
    checkpoints = list_checkpoints(run_dir)
    if resume and force:
        raise InputError("force: cannot be combined with resume")
    if resume:
        if not checkpoints:
            raise InputError(f"resume: no checkpoint in {run_dir / 'checkpoints'}")
        return checkpoints
    present = [name for name in RUN_OUTPUTS if (run_dir / name).exists()]
    if present and not force:
        kind = "a finished" if (run_dir / "final" / "model.zip").is_file() else "a started"
        what = f"{kind} run of {checkpoints[0][0]} steps" if checkpoints else "an earlier run"
        raise InputError(
            f"out: {run_dir} holds {what}; continue it (resume), overwrite it (force), or "
            "choose another folder"
        )
    for name in present:  # --force: only what a run writes, nothing else in the folder
        path = run_dir / name
        shutil.rmtree(path) if path.is_dir() else path.unlink()
    return []


def _round_up(requested: int, start: int, rollout: int) -> int:
    """The first whole-rollout count at or above ``requested`` (counted from ``start``)."""
    return start + math.ceil(max(requested - start, 0) / rollout) * rollout


def _resume_model(checkpoints: list[tuple[int, Path]], venv: Any, hp: dict, run_dir: Path):
    """The newest checkpoint with its statistics; refuse to go on without them."""
    steps, path = checkpoints[0]
    stats = find_stats(path)
    if stats is None:
        pkl = find_stats(path, ".pkl")
        hint = (
            f"; {pkl.name} is a pickle (runs code when loaded): convert it, if you trust it, "
            f"with `python -m agents.model_io {pkl}`"
            if pkl is not None
            else "; delete that checkpoint to resume from an older one"
        )
        raise InputError(
            f"resume: {path} has no normalisation statistics ({stats_path_for(path).name}); "
            f"refusing to train on without them{hint}"
        )
    doc = read_stats(stats, "resume")
    if hp["normalize"] is not None and not doc["norm_obs"]:
        raise InputError(f"resume: {stats} holds no statistics, but the config normalises")
    if doc["norm_obs"] or doc["norm_reward"]:
        venv = _vn_from_stats(doc, venv)
    model = load_ppo_safely(
        path,
        env=venv,
        schedules=schedules(hp["ppo"]),
        option="resume",
        tensorboard_log=str(run_dir / "tb"),
    )
    return model, venv, steps


def _new_model(venv: Any, hp: dict, seed: int, verbose: int, run_dir: Path):
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

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
    return model, venv


def _eval_venv(hp: dict, env_id: str, seed: int) -> Any:
    from stable_baselines3.common.vec_env import VecNormalize

    # The same wrapper stack as training's (SB3 syncs VecNormalize through it layer by layer).
    kind = "batch" if hp["vec_env"] == "batch" else "dummy"
    eval_venv = make_venv(hp["eval_env_id"] or env_id, 1, seed + 10_000, hp["env_kwargs"], kind)
    if hp["normalize"] is None:
        return eval_venv
    kwargs = {k: v for k, v in hp["normalize"].items() if k not in ("norm_reward", "training")}
    return VecNormalize(eval_venv, training=False, norm_reward=False, **kwargs)


def resume_command(info: dict[str, Any]) -> str:
    """The command that continues this run to its target."""
    args = ["lrp-gym", "train"]
    if info.get("config_arg"):
        args += ["--config", info["config_arg"]]
    args += ["--env", info["env_id"], "--out", info["run_dir"], "--seed", str(info["seed"])]
    return shlex.join([*args, "--timesteps", str(info["target_timesteps"]), "--resume"])


# --------------------------------------------------------------------------- training
def train(
    config: str | Path | None = None,
    env_id: str | None = None,
    timesteps: int | None = None,
    out: str | Path | None = None,
    resume: bool = False,
    seed: int = 0,
    progress_bar: bool = True,
    verbose: int = 0,
    force: bool = False,
    log: Callable[[str], None] = print,
) -> dict[str, Any]:
    """Train PPO from a zoo-style config; returns the run info (also in ``run_info.json``).

    Parameters
    ----------
    config : path, optional
        Zoo-style hyperparameter YAML; default: the shipped ``configs/ppo.yaml``.
    env_id : str, optional
        Section (and env) to train; default: the file's first section.
    timesteps : int, optional
        Total env steps (overrides ``n_timesteps``), rounded up to whole rollouts.
    out : path, optional
        Run directory; default ``runs/ppo-<env_id>-s<seed>``.
    resume : bool
        Continue (or extend) the run in ``out`` from its newest checkpoint.
    seed : int
        Seeds torch, numpy, the training envs (``seed + rank``) and the eval env.
    force : bool
        Overwrite the outputs of an earlier run in ``out``.
    log : callable
        Receives one-line messages for the user (rounding, signals).

    Returns
    -------
    dict
        The run info; ``status`` is ``done`` or ``interrupted`` and ``files`` lists what the
        end of the run wrote.
    """
    env_id, raw = load_hyperparams(config, env_id)
    hp = split_hyperparams(raw)
    requested = int(timesteps) if timesteps is not None else hp["n_timesteps"]
    if requested < 1:
        raise InputError(f"timesteps: must be at least 1, got {requested}")
    run_dir = Path(out) if out is not None else Path("runs") / f"ppo-{env_id}-s{seed}"
    checkpoints = _prepare_run_dir(run_dir, resume, force)
    if checkpoints and requested <= checkpoints[0][0]:
        raise InputError(
            f"timesteps: the run already has {checkpoints[0][0]} steps; give a larger total "
            "to extend it"
        )
    model, venv, eval_venv, start = _build(hp, env_id, seed, verbose, run_dir, checkpoints)
    run_dir.mkdir(parents=True, exist_ok=True)
    info = _start_info(config, env_id, raw, hp, run_dir, seed, requested, start, model, resume)
    if info["target_timesteps"] != requested:
        log(
            f"timesteps: {requested} rounded up to {info['target_timesteps']} (PPO trains on "
            f"whole rollouts of n_steps {model.n_steps} x n_envs {model.n_envs})"
        )
    return _run(model, venv, eval_venv, hp, info, progress_bar, log)


def _build(hp: dict, env_id: str, seed: int, verbose: int, run_dir: Path, checkpoints: list):
    """Envs and model: new, or from the newest checkpoint; no worker is left behind on error."""
    import torch
    from stable_baselines3.common.utils import set_random_seed

    # Small MLPs: one thread avoids oversubscribing the cores the env workers need.
    torch.set_num_threads(1)
    set_random_seed(seed)
    venv = make_venv(env_id, hp["n_envs"], seed, hp["env_kwargs"], hp["vec_env"] or "dummy")
    eval_venv = None
    try:
        eval_venv = _eval_venv(hp, env_id, seed)
        if checkpoints:
            model, venv, start = _resume_model(checkpoints, venv, hp, run_dir)
        else:
            model, venv = _new_model(venv, hp, seed, verbose, run_dir)
            start = 0
    except BaseException:
        ck.close_venv(venv)
        if eval_venv is not None:
            ck.close_venv(eval_venv)
        raise
    return model, venv, eval_venv, start


def _start_info(config, env_id, raw, hp, run_dir, seed, requested, start, model, resume):
    previous_wall = 0.0
    info_path = run_dir / "run_info.json"
    if resume and info_path.is_file():
        previous_wall = float(json.loads(info_path.read_text()).get("wall_time_s") or 0.0)
    return {
        "command": shlex.join([Path(sys.argv[0]).name, *sys.argv[1:]]),
        "config": str(config if config is not None else DEFAULT_CONFIG),
        "config_arg": str(config) if config is not None else None,
        "env_id": env_id,
        "eval_env_id": hp["eval_env_id"] or env_id,
        "run_dir": str(run_dir),
        "seed": seed,
        "n_envs": hp["n_envs"],
        "vec_env": hp["vec_env"] or "dummy",
        "hyperparams": raw,
        "requested_timesteps": requested,
        "target_timesteps": _round_up(requested, start, model.n_steps * model.n_envs),
        "resumed_from": start if resume else None,
        "status": "running",
        "wall_time_s": previous_wall,
    }


def _run(model, venv, eval_venv, hp, info, progress_bar, log) -> dict[str, Any]:
    """Learn to the target; whatever happens, save a checkpoint and stop the workers."""
    run_dir, start, target = Path(info["run_dir"]), model.num_timesteps, info["target_timesteps"]
    n_envs = model.n_envs
    evaluation = ck.make_evaluation(
        run_dir,
        eval_venv,
        int(float(hp["eval_freq"] or 10_000)),
        int(hp["n_eval_episodes"] or 10),
        n_envs,
        start,
    )
    write_json(run_dir / "run_info.json", info)
    t0, status = time.perf_counter(), "failed"
    with ck.StopSignals(log) as stop:
        periodic = ck.RunCallback(run_dir, int(float(hp["checkpoint_freq"] or 10_000)), stop)
        callbacks = [periodic, evaluation]
        if progress_bar:
            callbacks.append(ck.ProgressCallback(start, target))
        try:
            model.learn(
                target - start,
                callback=callbacks,
                reset_num_timesteps=start == 0,
                tb_log_name="PPO",
            )
            status = "interrupted" if stop.requested else "done"
            if status == "done":
                ck.evaluate_now(evaluation, model)
        except KeyboardInterrupt:  # a second signal: stop at once, still keep the work
            status = "interrupted"
        finally:
            files = _finish(model, venv, eval_venv, evaluation, info, status, t0)
    info["files"] = [str(p) for p in files]
    return info


def _finish(model, venv, eval_venv, evaluation, info, status, t0) -> list[Path]:
    """End-of-run outputs: checkpoint, final model, run info, learning curve; workers stopped."""
    run_dir = Path(info["run_dir"])
    files: list[Path] = []
    try:
        path = ck.checkpoint_path(run_dir, model.num_timesteps)
        files += save_model(model, path) if not path.is_file() else [path, stats_path_for(path)]
        if status == "done":
            files += save_model(model, run_dir / "final" / "model.zip")
    finally:
        ck.close_venv(venv)
        ck.close_venv(eval_venv)
    best = run_dir / "best" / "best_model.zip"
    if best.is_file():
        files += [best, stats_path_for(best)]
    info.update(
        status=status,
        timesteps=int(model.num_timesteps),
        wall_time_s=round(info["wall_time_s"] + time.perf_counter() - t0, 1),
        last_eval=ck.last_eval(evaluation),
        best_mean_reward=float(evaluation.best_mean_reward),
        checkpoint=str(files[0]),
        resume_command=resume_command(info),
    )
    files.append(write_json(run_dir / "run_info.json", info))
    if evaluation.evaluations_timesteps:
        files.append(run_dir / "eval" / "evaluations.npz")
        title = f"PPO on {info['env_id']}"
        files.append(plot_learning_curve(run_dir, run_dir / "learning_curve.png", title))
    return files
