"""``lrp-gym bench``: speed of the radar chain, AMCL and the registered environments."""

from __future__ import annotations

import importlib

import typer
from rich.table import Table

from lrp_gym.commands._common import console, print_json
from lrp_gym.config import load_scenario
from lrp_gym.errors import InputError

# component -> (module, function); each function takes (scenario_config, seconds) -> dict
COMPONENTS = {
    "radar": ("lrp_gym.radar.bench", "bench_radar"),
    "tracking": ("lrp_gym.tracking.bench", "bench_tracking"),
    "amcl": ("lrp_gym.localization.bench", "bench_amcl"),
    "env": ("lrp_gym.envs.bench", "bench_envs"),
}


def bench(
    component: str = typer.Option(
        "all", "--component", "-c", help="radar, tracking, amcl, env or all."
    ),
    scenario: str = typer.Option("ipin2023", help="Scenario for the component benchmarks."),
    seconds: float = typer.Option(3.0, min=0.1, help="Measuring time per figure."),
    json_out: bool = typer.Option(False, "--json", help="Print the figures as JSON."),
) -> None:
    """Measure speed on one core: radar frames/s, AMCL update time, env steps/s."""
    if not seconds < float("inf"):  # nan and inf pass typer's min=0.1
        raise InputError(f"--seconds: must be a finite number, got {seconds:g}")
    names = list(COMPONENTS) if component == "all" else [component]
    unknown = [n for n in names if n not in COMPONENTS]
    if unknown:
        raise InputError(
            f"--component: unknown {unknown[0]!r}; choose from {', '.join(COMPONENTS)} or all"
        )
    cfg = load_scenario(scenario)
    _pin_to_one_core()
    results: dict = {}
    for name in names:
        module, func = COMPONENTS[name]
        fn = getattr(importlib.import_module(module), func)
        if not json_out:
            console.print(f"[dim]benchmarking {name} ...[/]")
        results.update(fn(cfg, seconds))
    if json_out:
        print_json(results)
        return
    table = Table(title="lrp-gym benchmark (one core)")
    table.add_column("figure")
    table.add_column("value", justify="right")

    def rows(prefix: str, data: dict) -> None:
        for k, v in data.items():
            if isinstance(v, dict):
                rows(f"{prefix}{k}.", v)
            else:
                table.add_row(prefix + k, f"{v:,.3f}" if isinstance(v, float) else str(v))

    rows("", results)
    console.print(table)


def _pin_to_one_core() -> None:
    """Run on a single CPU so the figures mean 'one core' (Linux; elsewhere a no-op)."""
    import os

    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})


def register(app: typer.Typer) -> None:
    app.command("bench")(bench)
