"""``lrp-gym train``: PPO from a zoo-style hyperparameter file (see :mod:`agents.ppo`)."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console

from lrp_gym.commands._common import as_flags, console, print_json
from lrp_gym.errors import InputError


def train(
    config: Path = typer.Option(
        None,
        "--config",
        metavar="FILE.yaml",
        help="Zoo-style hyperparameter YAML (default: the shipped configs/ppo.yaml).",
    ),
    env: str = typer.Option(
        None,
        "--env",
        metavar="ENV_ID",
        help="Env id (section of the config); default: its first section.",
    ),
    timesteps: int = typer.Option(
        None,
        "--timesteps",
        metavar="N",
        help="Total env steps (overrides n_timesteps), rounded up to whole PPO rollouts of "
        "n_steps x n_envs.",
    ),
    out: Path = typer.Option(
        None,
        "--out",
        metavar="FOLDER",
        help="Run folder: checkpoints, best and final model, learning curve, run_info.json "
        "(default runs/ppo-<env>-s<seed>).",
    ),
    resume: bool = typer.Option(
        False,
        "--resume",
        help="Continue or extend the run in --out from its newest checkpoint (to --timesteps).",
    ),
    force: bool = typer.Option(
        False, "--force", help="Overwrite the outputs of an earlier run in --out."
    ),
    seed: int = typer.Option(0, "--seed", metavar="N", help="Seed of torch, numpy and the envs."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar."),
    json_out: bool = typer.Option(
        False, "--json", help="Print the run info as JSON to stdout (messages go to stderr)."
    ),
    export: Path = typer.Option(
        None,
        "--export",
        metavar="FOLDER",
        help="After training, ship the best model (+ statistics, + eval JSON) to this folder.",
    ),
    export_episodes: int = typer.Option(
        50,
        "--export-episodes",
        metavar="N",
        help="Episodes of the shipped model's final eval on LRPRadarNav-v0.",
    ),
) -> None:
    """Train PPO; checkpoints, best model and statistics go to the run folder (--out).

    Every run ends with a checkpoint, also on Ctrl-C or SIGTERM (exit 130, resume command shown).
    """
    from agents.ppo import train as run

    if export_episodes < 1:
        raise InputError(f"--export-episodes: must be at least 1, got {export_episodes}")
    say = Console(stderr=True, highlight=False) if json_out else console
    flags = dict(config="--config", env_id="--env", out="--out", resume="--resume")
    with as_flags(**flags, force="--force", timesteps="--timesteps"):
        info = run(
            config,
            env,
            timesteps,
            out,
            resume,
            seed,
            progress_bar=progress and not json_out,
            force=force,
            log=lambda msg: _line(say, msg),
        )
    for path in info["files"]:
        _line(say, f"wrote {path}")
    _report(say, info)
    if info["status"] == "interrupted":
        if json_out:
            print_json(info)
        raise typer.Exit(130)
    if export is not None:
        info["export"] = _export(say, info["run_dir"], export, export_episodes)
    if json_out:
        print_json(info)


def _export(say: Console, run_dir: str, export: Path, episodes: int) -> dict:
    """Ship the run's best model to ``export`` and evaluate it there."""
    from agents.ppo import export_model

    with as_flags(model_path="--export", run_dir="--export"):
        doc = export_model(run_dir, export, episodes=episodes)
    for name in (doc["model"], doc["statistics"], "ppo_lrp_nav.json"):
        _line(say, f"wrote {Path(export) / name}")
    fe = doc["final_eval"]
    say.print(
        f"shipped {export}/{doc['model']}: on {fe['env_id']} success "
        f"{100 * fe['success_rate']:.0f} % over {fe['episodes']} episodes"
    )
    return doc


def _line(say: Console, text: str) -> None:
    """A plain line, never wrapped (paths and the resume command stay copyable)."""
    say.print(text, markup=False, highlight=False, soft_wrap=True)


def _report(say: Console, info: dict) -> None:
    """One status line, and for a stopped run what was saved and how to resume."""
    last = info.get("last_eval")
    evaluated = (
        f"; eval at {last['timesteps']} steps: mean return {last['mean_reward']:.2f}"
        + (f", success {100 * last['success_rate']:.0f} %" if "success_rate" in last else "")
        if last
        else ""
    )
    say.print(
        f"[bold]{info['status']}[/]: {info['timesteps']} of {info['target_timesteps']} steps "
        f"of {info['env_id']} in {info['wall_time_s']:.0f} s{evaluated}"
    )
    if info["status"] == "interrupted":
        _line(say, f"saved checkpoint {info['checkpoint']}")
        _line(say, f"resume with: {info['resume_command']}")


def register(app: typer.Typer) -> None:
    app.command("train", short_help="Train PPO; safe to interrupt and resume.")(train)
