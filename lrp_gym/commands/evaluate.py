"""``lrp-gym evaluate``: any agent on fixed seeds, one metrics table (see :mod:`agents.evaluate`)."""

from __future__ import annotations

from pathlib import Path

import typer

from lrp_gym.commands._common import SetHelp, console, parse_sets, print_json
from lrp_gym.errors import InputError

AGENT_NAMES = ("pure-pursuit", "ppo", "random", "oracle")


def evaluate(
    agent: str = typer.Option(
        "pure-pursuit", "--agent", help="pure-pursuit | ppo | random | oracle"
    ),
    model: Path = typer.Option(None, "--model", help="PPO model zip (default: the shipped one)."),
    env: str = typer.Option(
        None, "--env", help="Env id (default LRPRadarNav-v0; oracle: LRPRadarNavOracle-v0)."
    ),
    scenario: str = typer.Option(
        None, "--scenario", help="Scenario YAML or name (default: sampled goals in the paper room)."
    ),
    task: str = typer.Option(
        None,
        "--task",
        help="path | goal: override the scenario's task mode (e.g. sampled goals in another "
        "layout).",
    ),
    episodes: int = typer.Option(
        20, "--episodes", help="Number of episodes (seeds seed, seed+1, ...)."
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of the first episode."),
    json_out: bool = typer.Option(False, "--json", help="Print the metrics as JSON only."),
    gif: Path = typer.Option(None, "--gif", help="Write the first episode as an animated GIF."),
    out: Path = typer.Option(None, "--out", help="Also write the metrics JSON to this file."),
    sets: list[str] = typer.Option(None, "--set", help=SetHelp),
) -> None:
    """Evaluate an agent: success, collisions, time to goal, localisation and cross-track error."""
    if agent not in AGENT_NAMES:
        raise InputError(
            f"--agent: unknown agent {agent!r}; choose one of {', '.join(AGENT_NAMES)}"
        )
    if episodes < 1:
        raise InputError(f"--episodes: must be at least 1, got {episodes}")
    if model is not None and agent != "ppo":
        raise InputError("--model: only used with --agent ppo")
    if task is not None and task not in ("path", "goal"):
        raise InputError(f"--task: must be 'path' or 'goal', got {task!r}")
    from agents import evaluate as ev
    from lrp_gym.commands._common import write_json
    from lrp_gym.config import deep_merge

    overrides = parse_sets(sets, scenario)
    if task is not None:
        overrides = deep_merge(overrides, {"task": {"mode": task}})
    env_obj = ev.make_eval_env(
        agent, env, scenario, render_mode="rgb_array" if gif else None, overrides=overrides or None
    )
    policy = ev.make_agent(agent, env_obj, model, seed)
    env_id = env_obj.spec.id if env_obj.spec is not None else env

    def show(res) -> None:
        if not json_out:
            mark = (
                "[green]goal[/]"
                if res.success
                else ("[red]collision[/]" if res.collision else "[yellow]timeout[/]")
            )
            err = f"{res.loc_error_m.mean():.3f}" if res.steps else "-"
            console.print(
                f"seed {res.seed}: {mark} after {res.steps} steps, mean loc error {err} m"
            )

    summary = ev.evaluate(policy, env_obj, episodes, seed, gif_path=gif, progress=show)
    env_obj.close()
    doc = {
        "agent": agent,
        "env_id": env_id,
        "scenario": scenario,
        "task": task,
        "model": str(model or ev.DEFAULT_MODEL) if agent == "ppo" else None,
        **ev.public(summary),
    }
    if out is not None:
        write_json(doc, out)
    if json_out:
        print_json(doc)
        return
    console.print(
        ev.summary_table(summary, title=f"{agent} on {env_id}, seeds {seed}..{seed + episodes - 1}")
    )
    if gif:
        console.print(f"wrote {gif}")


def register(app: typer.Typer) -> None:
    app.command("evaluate")(evaluate)
