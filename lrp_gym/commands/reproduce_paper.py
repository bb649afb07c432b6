"""``lrp-gym reproduce-paper``: the paper's positioning experiment (look-up table vs AMCL)."""

from __future__ import annotations

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from lrp_gym.commands._common import (
    ScenarioArg,
    SetHelp,
    console,
    parse_sets,
    save_figure,
    write_json,
)
from lrp_gym.config import load_scenario
from lrp_gym.errors import InputError
from lrp_gym.experiments.reproduce import PAPER, Reproduction, reproduce

err_console = Console(stderr=True)


def plot_errors(result: Reproduction, title: str = ""):
    """Figure in the style of the paper's error plot: LUT markers, AMCL mean +- std."""
    import matplotlib.pyplot as plt

    pos = np.arange(1, result.lut_errors_m.shape[1] + 1)
    fig, ax = plt.subplots(figsize=(7, 3.5))
    runs = len(result.amcl_errors_m)
    series = [
        (result.lut_errors_m, "s", "tab:orange", "look-up table"),
        (result.amcl_errors_m, "o-", "tab:blue", f"AMCL (mean +- std, {runs} runs)"),
    ]
    if result.grid_errors_m is not None:
        series.append((result.grid_errors_m, "^--", "tab:green", "grid filter (mean +- std)"))
    for errors, fmt, color, label in series:
        mean, std = errors.mean(0), errors.std(0)
        # An error is never negative: the lower whisker stops at zero.
        yerr = np.vstack([np.minimum(std, mean), std])
        ax.errorbar(pos, mean, yerr=yerr, fmt=fmt, color=color, capsize=3, label=label)
    ax.set_xlabel("position on the path")
    ax.set_ylabel("position error [m]")
    ax.set_yscale("symlog", linthresh=0.1)
    ax.set_ylim(bottom=0.0)
    ax.set_xticks(pos)
    ax.grid(True, alpha=0.3)
    ax.legend()
    if title:
        ax.set_title(title)
    return fig


def reproduce_paper(
    scenario: str = typer.Option("ipin2023", "--scenario", help=ScenarioArg),
    runs: int = typer.Option(10, "--runs", help="Independent runs."),
    seed: int = typer.Option(0, "--seed", help="Root seed."),
    noise: str = typer.Option("off", "--noise", help="Thermal noise: off (the paper) or on."),
    fingerprints: str = typer.Option(
        "radar", "--fingerprints", help="radar (full chain) or true (bypass radar and tracker)."
    ),
    particles: int | None = typer.Option(None, "--particles", help="Override N0 (and max)."),
    estimator: str = typer.Option(
        "cluster",
        "--estimator",
        help="AMCL pose estimate: cluster (heaviest cluster, the project default) or best_k "
        "(the paper's rule: 20 best particles within 15 cm of the best).",
    ),
    localizer: str = typer.Option(
        "amcl",
        "--localizer",
        help="amcl, or grid: also run the histogram filter (same models as AMCL, slow) on the "
        "same detections and odometry, and report its errors next to AMCL's.",
    ),
    json_path: str | None = typer.Option(
        None, "--json", help="Write the results to this JSON file."
    ),
    plot_path: str | None = typer.Option(None, "--plot", help="Save the error figure here."),
    sets: list[str] = typer.Option(None, "--set", help=SetHelp),
) -> None:
    """Run the full chain (radar, CFAR, tracking, look-up table, AMCL) along the scenario's path
    and compare the per-position errors with the paper's."""
    if runs < 1:
        raise InputError(f"--runs: must be at least 1, got {runs}")
    if noise not in ("off", "on"):
        raise InputError(f"--noise: expected off or on, got {noise!r}")
    if fingerprints not in ("radar", "true"):
        raise InputError(f"--fingerprints: expected radar or true, got {fingerprints!r}")
    if estimator not in ("cluster", "best_k"):
        raise InputError(f"--estimator: expected cluster or best_k, got {estimator!r}")
    if localizer not in ("amcl", "grid"):
        raise InputError(f"--localizer: expected amcl or grid, got {localizer!r}")
    if particles is not None and particles < 10:
        raise InputError(f"--particles: must be at least 10, got {particles}")
    cfg = load_scenario(scenario).with_overrides(parse_sets(sets, scenario))
    if cfg.localization.method == "grid":  # --set localization.method=grid means the same
        localizer = "grid"
    over: dict = {"radar": {"noise": noise == "on"}}
    if particles is not None:
        over["localization"] = {
            "initial_particles": particles,
            "max_particles": particles,
            "min_particles": min(cfg.localization.min_particles, particles),
        }
    cfg = cfg.with_overrides(over)
    if len(cfg.task.path) < 2:
        raise InputError(f"--scenario: {cfg.name} has no path (task.path needs 2+ waypoints)")

    def progress(run: int, info: dict) -> None:
        grid = info.get("grid_mean_error_m")
        err_console.print(
            f"run {run + 1}/{runs}: LUT mean error {info['lut_mean_error_m']:.3f} m, "
            f"AMCL mean error {info['amcl_mean_error_m']:.3f} m"
            + (f", grid mean error {grid:.3f} m" if grid is not None else ""),
            highlight=False,
        )

    result = reproduce(
        cfg,
        runs=runs,
        seed=seed,
        progress=progress,
        true_fingerprints=fingerprints == "true",
        estimator=estimator,
        localizer=localizer,
    )
    data = result.to_dict()
    table = Table(title=f"{cfg.name}: position errors [m] (noise {noise}, {runs} runs)")
    grid = data.get("grid")
    cols = ("pos", "LUT mean", "AMCL mean", "AMCL std", "particles")
    for col in cols + (("grid mean", "grid std") if grid else ()):
        table.add_column(col, justify="right")
    for i in range(data["positions"]):
        extra = (
            (f"{grid['mean_errors_m'][i]:.3f}", f"{grid['std_errors_m'][i]:.3f}") if grid else ()
        )
        table.add_row(
            str(i + 1),
            f"{data['lut']['errors_m'][i]:.3f}",
            f"{data['amcl']['mean_errors_m'][i]:.3f}",
            f"{data['amcl']['std_errors_m'][i]:.3f}",
            f"{data['amcl']['mean_particles'][i]:.0f}",
            *extra,
        )
    console.print(table)
    conv = data["amcl"]["converged_after"]
    console.print(
        f"AMCL mean error {data['amcl']['mean_error_m']:.3f} m (paper ~{PAPER['amcl_mean_error_m']} m); "
        f"converged after {conv if conv is not None else 'never'} (paper ~{PAPER['amcl_converged_after']}); "
        f"LUT mean error {data['lut']['mean_error_m']:.3f} m, {data['lut']['entries']} entries "
        f"(paper {PAPER['lut_entries']}; fails at 9 and 12 with ~3.5 m and ~1 m)",
        highlight=False,
    )
    if grid:
        conv = grid["converged_after"]
        console.print(
            f"grid filter mean error {grid['mean_error_m']:.3f} m, converged after "
            f"{conv if conv is not None else 'never'} (same detections and odometry as AMCL)",
            highlight=False,
        )
    ms = data["frame_ms"]
    console.print(
        "time per frame: " + ", ".join(f"{k} {v:.2f} ms" for k, v in ms.items()), highlight=False
    )
    if json_path:
        write_json(data, json_path)
    if plot_path:
        save_figure(plot_errors(result, f"{cfg.name}, noise {noise}"), plot_path)


def register(app: typer.Typer) -> None:
    app.command("reproduce-paper")(reproduce_paper)
