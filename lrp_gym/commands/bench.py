"""``lrp-gym bench``: speed of the radar chain, AMCL and the registered environments."""

from __future__ import annotations

import importlib

import typer
from rich.table import Table

from lrp_gym.commands._common import (
    at_least,
    check_output,
    choice,
    console,
    force_option,
    json_option,
    load_config,
    out_option,
    print_json,
    scenario_argument,
    sets_option,
    write_json,
    wrote,
)

# component -> (module, function); each function takes (scenario_config, seconds) -> dict
COMPONENTS = {
    "radar": ("lrp_gym.radar.bench", "bench_radar"),
    "tracking": ("lrp_gym.tracking.bench", "bench_tracking"),
    "amcl": ("lrp_gym.localization.bench", "bench_amcl"),
    "env": ("lrp_gym.envs.bench", "bench_envs"),
    "vector": ("lrp_gym.envs.vector_bench", "bench_vector"),
}
#: ``all`` leaves out the vector bench (minutes: up to 256 robots, both fidelities).
DEFAULT_COMPONENTS = ("radar", "tracking", "amcl", "env")


def bench(
    scenario: str = scenario_argument(),
    component: str = typer.Option(
        "all",
        "--component",
        "-c",
        metavar="NAME",
        help="radar, tracking, amcl, env, vector (batched env against the single env, "
        "N = 1, 8, 64, 256; minutes) or all (all but vector).",
    ),
    seconds: float = typer.Option(
        3.0, "--seconds", metavar="SECONDS", help="Measuring time per figure [s] (>= 0.1)."
    ),
    sets: list[str] = sets_option(),
    out: str | None = out_option("the figures as JSON"),
    force: bool = force_option(),
    json_out: bool = json_option("the figures"),
) -> None:
    """Measure speed on one core: radar frames/s, AMCL update time, env steps/s."""
    at_least(seconds, 0.1, "--seconds")
    choice(component, (*COMPONENTS, "all"), "--component")
    names = list(DEFAULT_COMPONENTS) if component == "all" else [component]
    out_path = check_output(out, "--out", force, (".json",))
    cfg = load_config(scenario, sets)
    _pin_to_one_core()
    results: dict = {"machine": _machine()}
    for name in names:
        module, func = COMPONENTS[name]
        fn = getattr(importlib.import_module(module), func)
        if not json_out:
            console.print(f"[dim]benchmarking {name} ...[/]")
        results.update(fn(cfg, seconds))
    if out_path is not None:
        write_json(results, out_path)
    if json_out:
        print_json(results)
        if out_path is not None:
            wrote(out_path, quiet=True)
        return
    table = Table(title="lrp-gym benchmark (one core; units in the figure names)")
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
    if out_path is not None:
        wrote(out_path)


def _machine() -> dict:
    """CPU count and load before the run: speeds from a busy machine are not comparable."""
    import os

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return {"cpus": os.cpu_count(), "load_avg_1min": load}


def _pin_to_one_core() -> None:
    """Run on a single CPU so the figures mean 'one core' (Linux; elsewhere a no-op)."""
    import os

    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})


def register(app: typer.Typer) -> None:
    app.command("bench", short_help="Speed: radar frames/s, AMCL update time, env steps/s.")(bench)
