"""``lrp-gym train``: PPO from a zoo-style hyperparameter file (see :mod:`agents.ppo`)."""

from __future__ import annotations

from pathlib import Path

import typer

from lrp_gym.commands._common import console
from lrp_gym.errors import InputError


def train(
    config: Path = typer.Option(
        Path("configs/ppo.yaml"), "--config", help="Zoo-style hyperparameter YAML."
    ),
    env: str = typer.Option(
        None, "--env", help="Env id (section of the config); default: its first section."
    ),
    timesteps: int = typer.Option(
        None, "--timesteps", help="Total env steps (overrides n_timesteps)."
    ),
    out: Path = typer.Option(None, "--out", help="Run folder; default runs/ppo-<env>-s<seed>."),
    resume: bool = typer.Option(
        False, "--resume", help="Continue from the newest checkpoint in --out."
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of torch, numpy and the envs."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar."),
    export: Path = typer.Option(
        None, "--export", help="After training, ship the best model (+ stats, + eval JSON) here."
    ),
    export_episodes: int = typer.Option(
        50,
        "--export-episodes",
        help="Episodes of the shipped model's final eval on LRPRadarNav-v0.",
    ),
) -> None:
    """Train PPO; checkpoints, best model and VecNormalize statistics go to the run folder.

    Interrupt with Ctrl-C and continue with --resume: model, normalisation statistics,
    timestep count and learning curve carry over.
    """
    from agents.ppo import export_model
    from agents.ppo import train as run

    if export_episodes < 1:
        raise InputError(f"--export-episodes: must be at least 1, got {export_episodes}")
    info = run(config, env, timesteps, out, resume, seed, progress_bar=progress)
    last = info.get("last_eval") or {}
    console.print(
        f"[bold]{info['status']}[/]: {info['timesteps']} steps of {info['env_id']} in "
        f"{info['wall_time_s']:.0f} s; last eval: mean return {last.get('mean_reward', float('nan')):.2f}, "
        f"success {100 * last.get('success_rate', float('nan')):.0f} %"
    )

    if export is not None:
        run_dir = Path(out) if out is not None else Path("runs") / f"ppo-{info['env_id']}-s{seed}"
        doc = export_model(run_dir, export, episodes=export_episodes)
        fe = doc["final_eval"]
        console.print(
            f"shipped {export}/{doc['model']}: on {fe['env_id']} success "
            f"{100 * fe['success_rate']:.0f} % over {fe['episodes']} episodes"
        )


def register(app: typer.Typer) -> None:
    app.command("train")(train)
