"""``lrp-gym robustness``: perturbation x severity matrix (see :mod:`lrp_gym.experiments.robustness`)."""

from __future__ import annotations

from pathlib import Path

import typer

from lrp_gym.commands._common import SetHelp, console, parse_sets, print_json, save_figure
from lrp_gym.errors import InputError


def _floats(text: str, flag: str) -> list[float]:
    try:
        out = [float(t) for t in text.replace(",", " ").split()]
    except ValueError:
        raise InputError(f"{flag}: expected numbers separated by commas, got {text!r}") from None
    if not out:
        raise InputError(f"{flag}: give at least one value")
    return out


def robustness(
    agent: str = typer.Option(
        "pure-pursuit", "--agent", help="pure-pursuit | ppo | oracle | random"
    ),
    model: Path = typer.Option(None, "--model", help="PPO model zip (default: the shipped one)."),
    env: str = typer.Option(
        "LRPRadarNavFast-v0", "--env", help="Env id: LRPRadarNavFast-v0 or LRPRadarNav-v0."
    ),
    task: str = typer.Option(
        "path", "--task", help="path (paper scenario ipin2023) | goal (sampled goals)."
    ),
    episodes: int = typer.Option(
        10, "--episodes", help="Episodes per cell (seeds seed, seed+1, ...)."
    ),
    severities: str = typer.Option(
        "0.25,0.5,1", "--severities", help="Comma-separated severities in [0, 1]."
    ),
    perturbations: str = typer.Option(
        None, "--perturbations", help="Comma-separated perturbation names (default: all)."
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of the first episode of every cell."),
    json_out: bool = typer.Option(False, "--json", help="Print the matrix as JSON only."),
    sets: list[str] = typer.Option(None, "--set", help=SetHelp),
    plot: Path = typer.Option(
        None, "--plot", help="Write heatmaps (success, p95 error) to this image."
    ),
) -> None:
    """Closed-loop robustness: success, localisation error and kidnap recovery per perturbation x severity."""
    from lrp_gym.experiments import robustness as rb

    sev = _floats(severities, "--severities")
    names = (
        [t.strip() for t in perturbations.split(",") if t.strip()]
        if perturbations is not None
        else list(rb.PERTURBATION_NAMES)
    )
    rb._check(names, sev, episodes, agent)
    if model is not None and agent != "ppo":
        raise InputError("--model: only used with --agent ppo")
    if task not in ("path", "goal"):
        raise InputError(f"--task: must be 'path' or 'goal', got {task!r}")
    if plot is not None and plot.suffix.lower() not in (".png", ".pdf", ".svg", ".jpg"):
        raise InputError(f"--plot: use a .png, .pdf, .svg or .jpg file name, got {plot}")
    if seed < 0:
        raise InputError(f"--seed: must be non-negative, got {seed}")
    overrides = parse_sets(sets, "ipin2023" if task == "path" else None)

    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    total = episodes * (1 + len(names) * len(sev))
    with Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=Console(stderr=True),
        transient=json_out,
    ) as bar:
        job = bar.add_task("robustness", total=total)
        result = rb.run_matrix(
            agent,
            env,
            names,
            sev,
            episodes,
            seed,
            task,
            model=model,
            overrides=overrides,
            progress=lambda label: bar.update(job, description=f"{label:<26}"),
            on_episode=lambda: bar.advance(job),
        )
    if plot is not None:
        save_figure(rb.plot_matrix(result), plot)
    if json_out:
        print_json(result)
        return
    from rich.table import Table

    def f(v, pct=False):
        return "-" if v is None else (f"{100 * v:.0f} %" if pct else f"{v:.3f}")

    t = Table(
        title=f"{agent} on {env} ({task}), {episodes} episodes/cell, seeds {seed}..{seed + episodes - 1}"
    )
    for col in (
        "perturbation",
        "severity",
        "success",
        "collision",
        "p50 err m",
        "p95 err m",
        "localised",
        "recovery frames",
        f"recovered <= {rb.RECOVERY_BUDGET_FRAMES}",
    ):
        t.add_column(col, justify="left" if col == "perturbation" else "right")
    for c in result["cells"]:
        t.add_row(
            c["perturbation"],
            f"{c['severity']:g}",
            f(c["success_rate"], True),
            f(c["collision_rate"], True),
            f(c["p50_loc_error_m"]),
            f(c["p95_loc_error_m"]),
            f(c["time_localised"], True),
            f(c["recovery_frames"]),
            f(c["recovered_within_budget"], True),
        )
    console.print(t)
    if plot is not None:
        console.print(f"wrote {plot}")


def register(app: typer.Typer) -> None:
    app.command("robustness")(robustness)
