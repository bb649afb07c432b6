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
from lrp_gym.config import deep_merge, load_scenario
from lrp_gym.errors import InputError
from lrp_gym.experiments.reproduce import PAPER, Reproduction, reproduce

err_console = Console(stderr=True)


def plot_errors(result: Reproduction, title: str = ""):
    """Figure in the style of the paper's error plot: LUT markers, AMCL mean +- std."""
    import matplotlib.pyplot as plt

    pos = np.arange(1, result.lut_errors_m.shape[1] + 1)
    fig, ax = plt.subplots(figsize=(7, 3.5))
    runs = len(result.amcl_errors_m)
    series = (
        (result.lut_errors_m, "s", "tab:orange", "look-up table"),
        (result.amcl_errors_m, "o-", "tab:blue", f"AMCL (mean +- std, {runs} runs)"),
    )
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
    json_path: str | None = typer.Option(
        None, "--json", help="Write the results to this JSON file."
    ),
    plot_path: str | None = typer.Option(None, "--plot", help="Save the error figure here."),
    sets: list[str] = typer.Option(None, "--set", help=SetHelp),
    random_rooms: int = typer.Option(
        0,
        "--random-rooms",
        help="Instead of the scenario: AMCL on N generated rooms (room seeds 0..N-1), with the "
        "radar chain and with true fingerprints (see docs/scenarios.md).",
    ),
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
    if particles is not None and particles < 10:
        raise InputError(f"--particles: must be at least 10, got {particles}")
    if random_rooms < 0:
        raise InputError(f"--random-rooms: must not be negative, got {random_rooms}")
    if random_rooms:
        if fingerprints != "radar" or plot_path:
            raise InputError("--random-rooms: runs both fingerprint kinds and draws no --plot")
        over = deep_merge(parse_sets(sets, scenario), {"radar": {"noise": noise == "on"}})
        if particles is not None:
            over = deep_merge(over, _particles(particles, 200))
        _random_rooms(random_rooms, runs, seed, over, estimator, json_path)
        return
    cfg = load_scenario(scenario).with_overrides(parse_sets(sets, scenario))
    over: dict = {"radar": {"noise": noise == "on"}}
    if particles is not None:
        over.update(_particles(particles, cfg.localization.min_particles))
    cfg = cfg.with_overrides(over)
    if len(cfg.task.path) < 2:
        raise InputError(f"--scenario: {cfg.name} has no path (task.path needs 2+ waypoints)")

    def progress(run: int, info: dict) -> None:
        err_console.print(
            f"run {run + 1}/{runs}: LUT mean error {info['lut_mean_error_m']:.3f} m, "
            f"AMCL mean error {info['amcl_mean_error_m']:.3f} m",
            highlight=False,
        )

    result = reproduce(
        cfg,
        runs=runs,
        seed=seed,
        progress=progress,
        true_fingerprints=fingerprints == "true",
        estimator=estimator,
    )
    data = result.to_dict()
    table = Table(title=f"{cfg.name}: position errors [m] (noise {noise}, {runs} runs)")
    for col in ("pos", "LUT mean", "AMCL mean", "AMCL std", "particles"):
        table.add_column(col, justify="right")
    for i in range(data["positions"]):
        table.add_row(
            str(i + 1),
            f"{data['lut']['errors_m'][i]:.3f}",
            f"{data['amcl']['mean_errors_m'][i]:.3f}",
            f"{data['amcl']['std_errors_m'][i]:.3f}",
            f"{data['amcl']['mean_particles'][i]:.0f}",
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
    ms = data["frame_ms"]
    console.print(
        "time per frame: " + ", ".join(f"{k} {v:.2f} ms" for k, v in ms.items()), highlight=False
    )
    if json_path:
        write_json(data, json_path)
    if plot_path:
        save_figure(plot_errors(result, f"{cfg.name}, noise {noise}"), plot_path)


def _particles(n: int, min_particles: int) -> dict:
    """Overrides for ``--particles``: N0 and the maximum, the minimum no larger."""
    return {
        "localization": {
            "initial_particles": n,
            "max_particles": n,
            "min_particles": min(min_particles, n),
        }
    }


def _random_rooms(
    n: int, runs: int, seed: int, over: dict, estimator: str, json_path: str | None
) -> None:
    """``--random-rooms``: the generated-room baseline, one line per room as it finishes."""
    from lrp_gym.experiments.rooms import summary, sweep

    def progress(r) -> None:
        err_console.print(
            f"room {r.seed}: {r.size_m[0]:.1f} x {r.size_m[1]:.1f} m, {r.obstacles} obstacles, "
            f"{r.reflectors} reflectors ({r.kinds}), {r.frames} frames: AMCL "
            f"{r.amcl_radar_m:.3f} m (true fingerprints {r.amcl_true_m:.3f} m)",
            highlight=False,
        )

    results = sweep(
        range(n), runs=runs, run_seed=seed, overrides=over, estimator=estimator, progress=progress
    )
    data = summary(results)
    table = Table(title=f"AMCL mean error (m) on {n} generated rooms ({runs} runs each)")
    for col in ("room", "size (m)", "obst.", "refl.", "kinds", "frames", "radar", "true fp"):
        table.add_column(col, justify="right")
    for r in results:
        table.add_row(
            str(r.seed),
            f"{r.size_m[0]:.1f} x {r.size_m[1]:.1f} x {r.size_m[2]:.1f}",
            str(r.obstacles),
            str(r.reflectors),
            r.kinds,
            str(r.frames),
            f"{r.amcl_radar_m:.3f}",
            f"{r.amcl_true_m:.3f}",
        )
    console.print(table)
    console.print(
        f"median AMCL mean error: {data['median_amcl_radar_m']:.3f} m with the radar chain, "
        f"{data['median_amcl_true_m']:.3f} m with true fingerprints",
        highlight=False,
    )
    if json_path:
        write_json(data, json_path)


def register(app: typer.Typer) -> None:
    app.command("reproduce-paper")(reproduce_paper)
