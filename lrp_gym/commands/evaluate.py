"""``lrp-gym evaluate``: any agent on fixed seeds, one metrics table (see :mod:`lrp_gym.experiments.episodes`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from lrp_gym.commands._cluster import (
    PolicyFactory,
    check_ray_options,
    ray_option,
    reject_random_agent,
    resume_option,
)
from lrp_gym.commands._common import (
    FIDELITIES,
    as_flags,
    check_distinct,
    check_output,
    check_random_rooms,
    choice,
    console,
    fidelity_option,
    force_option,
    json_option,
    out_option,
    overrides,
    plot_option,
    print_json,
    save_figure,
    scenario_argument,
    seed_option,
    sets_option,
    write_json,
    wrote,
)
from lrp_gym.errors import InputError

AGENT_NAMES = ("pure-pursuit", "ppo", "random", "oracle")
TASKS = ("path", "goal")


def agent_option() -> Any:
    """``--agent`` (shared with robustness)."""
    return typer.Option(
        "pure-pursuit", "--agent", metavar="NAME", help=f"{' | '.join(AGENT_NAMES)}."
    )


def agent_settings_option() -> Any:
    """``--agent-option KEY=VALUE`` (shared with robustness)."""
    return typer.Option(
        None,
        "--agent-option",
        metavar="KEY=VALUE",
        help="A pure pursuit setting (pure-pursuit and oracle; a field of "
        "agents.pure_pursuit.PurePursuitConfig), e.g. avoid_walls_when_unsure=false or "
        "creep_speed_mps=0.2; repeatable.",
    )


def agent_settings(agent: str, items: list[str] | None) -> dict[str, Any]:
    """``--agent-option`` items as typed settings (checked before any work)."""
    if not items:
        return {}
    from agents.pure_pursuit import parse_options
    from agents.registry import CONFIGURABLE_AGENTS

    if agent not in CONFIGURABLE_AGENTS:
        names = " or ".join(CONFIGURABLE_AGENTS)
        raise InputError(f"--agent-option: only for --agent {names}, not {agent}")

    try:
        return parse_options(items)
    except ValueError as err:
        raise InputError(f"--agent-option: {err}") from None


def model_option() -> Any:
    """``--model`` (shared with robustness)."""
    return typer.Option(
        None,
        "--model",
        metavar="FILE.zip",
        help="PPO model zip (default: the shipped one): the shipped model or your own runs. "
        "SB3 zips may hold pickles, which run code when loaded; lrp-gym reads them as plain "
        "JSON and refuses a pickled value it cannot rebuild safely.",
    )


def env_option() -> Any:
    """``--env``: the Gymnasium env id the agent drives in (shared with robustness)."""
    return typer.Option(
        None,
        "--env",
        metavar="ENV_ID",
        help="Env id the agent drives in (default LRPRadarNav-v0; --agent oracle: "
        "LRPRadarNavOracle-v0). For the radar model use --fidelity.",
    )


def task_option() -> Any:
    """``--task path|goal`` (shared with robustness)."""
    return typer.Option(
        None,
        "--task",
        metavar="path|goal",
        help="path: follow the scenario's path; goal: sampled start poses and goals in its "
        "room. Default: the scenario's task.mode (path for ipin2023).",
    )


def episodes_option(what: str = "Number of episodes", default: int = 20) -> Any:
    """``--episodes N`` (shared with robustness, which defaults to more)."""
    return typer.Option(
        default, "--episodes", metavar="N", help=f"{what} (seeds seed, seed+1, ...)."
    )


def num_envs_option() -> Any:
    """``--num-envs N``: robots driven at once in one batched env (shared with robustness)."""
    return typer.Option(
        1,
        "--num-envs",
        metavar="N",
        help="Robots driven at once in one batched env; the same episodes and numbers as "
        "one at a time.",
    )


def check_num_envs(num_envs: int) -> None:
    if num_envs < 1:
        raise InputError(f"--num-envs: must be at least 1, got {num_envs}")


def check_agent(agent: str, model: Path | None, task: str | None, episodes: int) -> None:
    """The checks evaluate and robustness share, before any work."""
    choice(agent, AGENT_NAMES, "--agent")
    if episodes < 1:
        raise InputError(f"--episodes: must be at least 1, got {episodes}")
    if model is not None and agent != "ppo":
        raise InputError("--model: only used with --agent ppo")
    choice(task, TASKS, "--task")


def evaluate(
    scenario: str = scenario_argument(),
    agent: str = agent_option(),
    agent_options: list[str] = agent_settings_option(),
    model: Path = model_option(),
    env: str = env_option(),
    task: str = task_option(),
    fidelity: str = fidelity_option(),
    sets: list[str] = sets_option(),
    episodes: int = episodes_option(),
    seed: int = seed_option("Seed of the first episode."),
    num_envs: int = num_envs_option(),
    ray: str = ray_option("the episodes, 5 seeds a task,"),
    resume: bool = resume_option(),
    out: Path = out_option("the metrics as JSON"),
    gif: Path = typer.Option(
        None, "--gif", metavar="FILE.gif", help="Write the first episode as an animated GIF."
    ),
    plot: Path = plot_option(
        "the reliability diagram of the localisation confidence (share of steps localised "
        "per confidence bin)"
    ),
    force: bool = force_option(),
    json_out: bool = json_option("the metrics"),
    random_rooms: int = typer.Option(
        0,
        "--random-rooms",
        metavar="N",
        help="Instead of the scenario: the agent on N generated rooms (room seeds 0..N-1), "
        "--episodes each (see docs/scenarios.md).",
    ),
) -> None:
    """Evaluate an agent: success, collisions, time to goal, localisation and cross-track
    error."""
    check_agent(agent, model, task, episodes)
    settings = agent_settings(agent, agent_options)
    check_num_envs(num_envs)
    choice(fidelity, FIDELITIES, "--fidelity")
    out_path = check_output(out, "--out", force, (".json",))
    gif_path = check_output(gif, "--gif", force, (".gif",))
    plot_path = check_output(plot, "--plot", force, (".png", ".pdf", ".svg"))
    check_distinct(out_path, gif_path, plot_path)
    _check_random_rooms(random_rooms, gif_path, ray)
    reject_random_agent(agent, ray)
    if ray is not None and gif_path is not None:
        raise InputError("--gif: not with --ray (run the episode to record without it)")
    over = overrides(scenario, sets, fidelity)
    study = dict(command="evaluate", agent=agent, model=model, env=env, task=task, seed=seed)
    study |= {"agent_options": settings} if settings else {}
    sidecar = check_ray_options(ray, resume, out_path, force, study | {"overrides": over})
    from agents import registry as ev
    from lrp_gym.config import deep_merge
    from lrp_gym.experiments import episodes as ep

    if task is not None:
        over = deep_merge(over, {"task": {"mode": task}})
    if random_rooms:
        job = dict(agent=agent, env_id=env, overrides=over, episodes=episodes, seed=seed)
        job |= dict(num_envs=num_envs)
        model_name = str(model or ev.DEFAULT_MODEL) if agent == "ppo" else None
        head = dict(agent=agent, sets=list(sets or []), agent_options=settings, model=model_name)
        factory = PolicyFactory(agent, model, seed, settings)
        from lrp_gym.commands._rooms_eval import random_rooms as run_rooms

        run_rooms(random_rooms, factory, job, head, (out_path, plot_path), json_out)
        return
    with as_flags(env_id="--env"):
        env_obj = ep.make_eval_env(
            agent, env, scenario, render_mode="rgb_array" if gif else None, overrides=over or None
        )
    with as_flags(model_path="--model", agent="--agent"):
        policy = ev.make_agent(agent, env_obj, model, seed, settings)
    env_id = env_obj.spec.id if env_obj.spec is not None else env
    cfg = ep.nav_env(env_obj).cfg
    try:
        with as_flags(n_episodes="--episodes", num_envs="--num-envs"):
            if ray is not None:
                show = None if json_out else _show
                run = dict(address=ray, sidecar=sidecar, resume=resume)
                summary = _on_ray(
                    PolicyFactory(agent, model, seed, settings), agent, seed, env, scenario,
                    over, episodes, num_envs, show, run,
                )  # fmt: skip
            else:
                summary = ep.run_episodes(
                    policy,
                    env_obj,
                    episodes,
                    seed,
                    gif_path=gif_path,
                    progress=None if json_out else _show,
                    num_envs=num_envs,
                )
    finally:
        env_obj.close()
    doc = {
        "agent": agent,
        "env_id": env_id,
        "scenario": scenario,
        "task": cfg.task.mode,
        "fidelity": cfg.radar.fidelity,
        "sets": list(sets or []),
        "agent_options": settings,
        "model": str(model or ev.DEFAULT_MODEL) if agent == "ppo" else None,
        **ep.public(summary),
    }
    if out_path is not None:
        write_json(doc, out_path)
    if sidecar is not None:
        sidecar.remove()  # the result is whole: the partial results are no longer needed
    title = (
        f"{agent} on {env_id} ({scenario}, {cfg.task.mode}), seeds {seed}..{seed + episodes - 1}"
    )
    if json_out:
        print_json(doc)
    else:
        console.print(ev.summary_table(summary, title=title))
        if summary.get("reliability"):
            console.print(ev.reliability_table(summary["reliability"]))
    if plot_path is not None:
        from lrp_gym.localization.plotting import plot_reliability

        fig = plot_reliability(summary["reliability"], title=f"Confidence reliability: {title}")
        save_figure(fig, plot_path)
    for p in (gif_path, out_path, plot_path):
        if p is not None:
            wrote(p, quiet=json_out)


def _check_random_rooms(n: int, gif_path: Path | None, ray: str | None) -> None:
    """``--random-rooms N``: not negative; no GIF and no Ray with it (checked before any work)."""
    check_random_rooms(n)
    for flag, value in (("--gif", gif_path), ("--ray", ray)):
        if n and value is not None:
            raise InputError(f"{flag}: not with --random-rooms (run one scenario for it)")


def _on_ray(factory, agent, seed, env, scenario, over, episodes, num_envs, show, run) -> dict:
    """The evaluation as Ray tasks (``run``: address, sidecar, resume); ``show`` each episode."""
    from lrp_gym.experiments.distributed import run_episodes_units

    def shown(_key, part) -> None:
        for res in part if show is not None else ():
            show(res)

    return run_episodes_units(
        factory, agent, env, scenario, over, episodes, seed,
        num_envs, on_result=shown, **run,
    )  # fmt: skip


def _show(res) -> None:
    mark = (
        "[green]goal[/]"
        if res.success
        else ("[red]collision[/]" if res.collision else "[yellow]timeout[/]")
    )
    err = f"{res.loc_error_m.mean():.3f}" if res.steps else "-"
    console.print(f"seed {res.seed}: {mark} after {res.steps} steps, mean loc error {err} m")


def register(app: typer.Typer) -> None:
    app.command("evaluate", short_help="Evaluate an agent on fixed seeds.")(evaluate)
