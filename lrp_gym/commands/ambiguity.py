"""``lrp-gym ambiguity``: the ambiguity map of a scenario's reflector layout."""

from __future__ import annotations

import time

import typer

from lrp_gym.commands._common import (
    at_least,
    check_distinct,
    check_output,
    console,
    force_option,
    json_option,
    load_config,
    out_option,
    plot_option,
    print_json,
    save_figure,
    scenario_argument,
    sets_option,
    write_json,
    wrote,
)


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
    scenario: str = scenario_argument(),
    grid_m: float = typer.Option(
        None, "--grid", metavar="METRES", help="Grid cell size [m] (default placement.grid_m)."
    ),
    sets: list[str] = sets_option(),
    out: str | None = out_option("the figures as JSON"),
    plot: str = plot_option("the ambiguity map"),
    force: bool = force_option(),
    json_out: bool = json_option("the figures"),
) -> None:
    """Analyse the fingerprint ambiguities of SCENARIO's reflector layout.

    Prints the ambiguous area fraction (systematic and random), whether the layout satisfies
    the symmetry constraint, and the number of distinct fingerprints at the look-up-table
    resolution.
    """
    from lrp_gym.placement.scenario import analyse_scenario

    at_least(grid_m, 1e-6, "--grid")
    out_path = check_output(out, "--out", force, (".json",))
    plot_path = check_output(plot, "--plot", force, (".png", ".pdf", ".svg"))
    check_distinct(out_path, plot_path)
    cfg = load_config(scenario, sets)
    start = time.perf_counter()
    result = analyse_scenario(cfg, grid_m)
    summary = result.summary() | {"elapsed_s": time.perf_counter() - start}
    if plot_path is not None:
        from lrp_gym.placement.plotting import plot_scenario_map

        save_figure(plot_scenario_map(cfg, result), plot_path)
        summary["plot"] = str(plot_path)
    if out_path is not None:
        write_json(summary, out_path)
    if json_out:
        print_json(summary)
    else:
        print_summary(summary)
        console.print(f"analysed in {summary['elapsed_s']:.2f} s")
    for p in (plot_path, out_path):
        if p is not None:
            wrote(p, quiet=json_out)


def register(app: typer.Typer) -> None:
    app.command("ambiguity", short_help="Fingerprint ambiguity analysis and map.")(ambiguity)
