"""Outputs of a training run that are read after it: the learning curve and a shipped model."""

from __future__ import annotations

import json
import shutil
import time
from pathlib import Path
from typing import Any

import numpy as np

from agents.registry import load_ppo
from lrp_gym.errors import InputError
from lrp_gym.experiments.episodes import make_eval_env, public, run_episodes
from lrp_gym.output import save_figure
from lrp_gym.output import write_json as _write


def write_json(path: Path, data: dict[str, Any]) -> Path:
    """Write JSON atomically (see :func:`lrp_gym.output.write_json`)."""
    return _write(data, path)


def plot_learning_curve(run_dir: str | Path, out_png: str | Path, title: str = "PPO") -> Path:
    """Write the learning curve of a run (:func:`learning_curve_figure`) to ``out_png``."""
    npz = Path(run_dir) / "eval" / "evaluations.npz"
    if not npz.is_file():
        raise InputError(f"no learning curve: {npz} is missing")
    with np.load(npz) as d:
        t, res = d["timesteps"], d["results"]
        succ = d["successes"] if "successes" in d and d["successes"].size else None
    return save_figure(learning_curve_figure(t, res, succ, title), out_png)


def learning_curve_figure(
    timesteps: np.ndarray,
    returns: np.ndarray,
    successes: np.ndarray | None = None,
    title: str = "PPO",
) -> Any:
    """Mean eval return (band: ±1 std over the eval episodes) and success rate against timesteps.

    Parameters
    ----------
    timesteps : ndarray, shape (n,)
        Training steps at each evaluation (EvalCallback's ``timesteps``).
    returns : ndarray, shape (n, episodes)
        Return of every eval episode (EvalCallback's ``results``).
    successes : ndarray, shape (n, episodes), optional
        1 where the episode reached its goal.
    title : str
        Figure title.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t, res, succ = np.asarray(timesteps), np.asarray(returns, float), successes
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    mean, std = res.mean(axis=1), res.std(axis=1)
    n_eval = res.shape[1]
    marker = "o" if len(t) < 3 else None
    ax.plot(t, mean, color="C0", marker=marker, label=f"mean return over {n_eval} eval episodes")
    # The band is the spread of single episodes, not a confidence interval of the mean.
    band = "mean ± 1 std over episodes"
    if len(t) > 1:
        ax.fill_between(t, mean - std, mean + std, color="C0", alpha=0.2, label=band)
    else:  # one evaluation: a band has no width, so draw it as an error bar
        ax.errorbar(t, mean, yerr=std, fmt="none", ecolor="C0", alpha=0.5, capsize=6, label=band)
    ax.set_xlabel("training timesteps [env steps]")
    ax.set_ylabel("episode return [sum of rewards]", color="C0")
    handles, labels = ax.get_legend_handles_labels()
    top = ax  # the legend goes on the upper axes so no curve is drawn over it
    if succ is not None and len(succ) == len(t):
        ax2 = ax.twinx()
        ax2.plot(t, 100 * succ.mean(axis=1), color="C1", marker=marker, label="success rate")
        ax2.set_ylabel(f"success rate [%] ({n_eval} episodes)", color="C1")
        ax2.set_ylim(-5, 105)
        h2, l2 = ax2.get_legend_handles_labels()
        handles, labels, top = handles + h2, labels + l2, ax2
    top.legend(handles, labels, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=3)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    return fig


#: the shipped model's JSON field -> the run_info.json field it copies, in this order
RUN_INFO_FIELDS = {
    "train_command": "command",
    **{key: key for key in ("config", "env_id", "seed", "timesteps", "wall_time_s", "hyperparams")},
}


def export_model(
    run_dir: str | Path,
    dest_dir: str | Path,
    name: str = "ppo_lrp_nav",
    which: str = "best",
    eval_env_id: str = "LRPRadarNav-v0",
    episodes: int = 50,
    seed: int = 1000,
) -> dict[str, Any]:
    """Ship a run's model: ``<name>.zip`` + ``vecnormalize.json`` + ``<name>.json``.

    The JSON holds the run info (command, timesteps, wall time) and a final evaluation of the
    exported model on ``eval_env_id`` (goal episodes on seeds ``seed, seed + 1, ...``).

    Parameters
    ----------
    which : {"best", "final"}
        EvalCallback's best model or the model at the end of training.
    """
    run_dir, dest = Path(run_dir), Path(dest_dir)
    src = _copy_model(run_dir, which, dest, name)
    summary, eval_s = _evaluate_model(dest / f"{name}.zip", eval_env_id, episodes, seed)
    info_path = run_dir / "run_info.json"
    run_info = json.loads(info_path.read_text()) if info_path.is_file() else {}
    doc = {
        "model": f"{name}.zip",
        "statistics": "vecnormalize.json",
        "source": str(src),
        **{key: run_info.get(field) for key, field in RUN_INFO_FIELDS.items()},
        "final_eval": {
            "env_id": eval_env_id,
            "episodes": episodes,
            "seed": seed,
            "eval_wall_time_s": round(eval_s, 1),
            **summary,
        },
    }
    write_json(dest / f"{name}.json", doc)
    return doc


def _copy_model(run_dir: Path, which: str, dest: Path, name: str) -> Path:
    """Copy the run's model and its normalisation statistics into ``dest``; return the source zip.

    Each file is written beside its target and renamed, so a reader never sees half a model.
    """
    from agents.model_io import find_stats

    src = run_dir / ("best/best_model.zip" if which == "best" else "final/model.zip")
    if not src.is_file():
        raise InputError(f"run_dir: {src} does not exist (has the run finished?)")
    stats = find_stats(src)
    if stats is None:
        raise InputError(f"run_dir: {src} has no normalisation statistics beside it")
    dest.mkdir(parents=True, exist_ok=True)
    for source, target in ((stats, dest / "vecnormalize.json"), (src, dest / f"{name}.zip")):
        tmp = target.with_name(target.name + ".tmp")
        shutil.copyfile(source, tmp)
        tmp.replace(target)
    return src


def _evaluate_model(
    model: Path, env_id: str, episodes: int, seed: int
) -> tuple[dict[str, Any], float]:
    """Public episode metrics of ``model`` on ``env_id`` (no per-episode rows) and the seconds
    from loading the model to the end of the episodes (the env's creation not counted)."""
    env = make_eval_env("ppo", env_id)
    t0 = time.perf_counter()
    policy = load_ppo(model, (env.observation_space, env.action_space))
    summary = public(run_episodes(policy, env, episodes, seed))
    env.close()
    summary.pop("per_episode", None)
    return summary, time.perf_counter() - t0
