"""``lrp-gym ambiguity``: the ambiguity map of a scenario's reflector layout."""

from __future__ import annotations

import time

import typer

from lrp_gym.commands._common import ScenarioArg, console, print_json, save_figure
from lrp_gym.config import load_scenario
from lrp_gym.errors import InputError


def print_summary(summary: dict) -> None:
    """Human-readable lines for an ambiguity summary."""
    ok = "[green]ok[/]" if summary["constraint_ok"] else "[red]violated[/]"
    console.print(
        f"ambiguous {100 * summary['ambiguous_fraction']:.2f} % of {summary['cells']} cells "
        f"(systematic {100 * summary['systematic_fraction']:.2f} %, random "
        f"{100 * summary['random_fraction']:.2f} %), {summary['ambiguity_groups']} groups; "
        f"grid {summary['grid_m']:g} m, tolerance {summary['tolerance_m']:.4f} m, "
        f"separation {summary['separation_m']:g} m"
    )
    console.print(
        f"constraint {ok} (margin {summary['constraint_margin_m']:.3f} m); "
        f"unique fingerprints {summary['unique_fingerprints']}"
    )
    for s in summary["constraint_structures"]:
        console.print(f"  - {s}", markup=False, highlight=False)


def ambiguity(
    scenario: str = typer.Argument(..., help=ScenarioArg),
    plot: str = typer.Option(None, "--plot", help="Write the ambiguity map to this image file."),
    grid_m: float = typer.Option(
        None, "--grid", help="Grid cell size in metres (default placement.grid_m)."
    ),
    json_out: bool = typer.Option(False, "--json", help="Print the figures as JSON."),
) -> None:
    """Analyse the fingerprint ambiguities of SCENARIO's reflector layout.

    Prints the ambiguous area fraction (systematic and random), whether the layout satisfies the
    symmetry constraint, and the number of distinct fingerprints at the look-up-table resolution.
    """
    from lrp_gym.placement.scenario import analyse_scenario

    if grid_m is not None and not (grid_m > 0 and grid_m < float("inf")):
        raise InputError(f"--grid: must be a positive finite number, got {grid_m:g}")
    cfg = load_scenario(scenario)
    start = time.perf_counter()
    result = analyse_scenario(cfg, grid_m)
    summary = result.summary() | {"elapsed_s": time.perf_counter() - start}
    if plot:
        from lrp_gym.placement.plot import plot_scenario_map

        save_figure(plot_scenario_map(cfg, result), plot)
        summary["plot"] = plot
    if json_out:
        print_json(summary)
        return
    print_summary(summary)
    console.print(
        f"analysed in {summary['elapsed_s']:.2f} s" + (f"; map written to {plot}" if plot else "")
    )


def register(app: typer.Typer) -> None:
    app.command("ambiguity")(ambiguity)
