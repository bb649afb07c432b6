"""``lrp-gym track``: drive the scenario path through the radar and the LRP tracker."""

from __future__ import annotations

import numpy as np
import typer
from rich.table import Table

from lrp_gym.commands._common import ScenarioArg, SetHelp, console, parse_sets, print_json
from lrp_gym.config import load_scenario
from lrp_gym.errors import InputError


def _fmt(x: float, fresh: bool = True) -> str:
    if not np.isfinite(x):
        return "[dim]-[/]"
    return f"{x:.3f}" if fresh else f"[yellow]{x:.3f}*[/]"


def track(
    scenario: str = typer.Argument(..., help=ScenarioArg),
    seed: int = typer.Option(0, "--seed", help="Seed of the radar noise."),
    json_out: bool = typer.Option(False, "--json", help="Print only the summary as JSON."),
    sets: list[str] = typer.Option(None, "--set", help=SetHelp),
    prior: bool = typer.Option(
        True,
        "--prior/--no-prior",
        help="Identify the reflectors with AMCL's last estimate moved by the odometry.",
    ),
    plot: str | None = typer.Option(
        None, "--plot", help="Save a figure of true, detected and tracked distances (PNG)."
    ),
    ego: bool = typer.Option(
        True,
        "--ego/--no-ego",
        help="Predict static points from the odometry (else the paper's constant-velocity model).",
    ),
) -> None:
    """Drive SCENARIO's task.path through the radar chain and the tracker.

    Prints, per frame and reflector, the true distance, the matched RCS-gated detection (raw)
    and the tracked distance (* = coasting or not yet confirmed), then the RMSEs, the frames
    with a track swap and the frames where some reflector had no fresh tracked distance.
    AMCL runs alongside on the gated detections, as in the env; its estimate is the prior.
    """
    from lrp_gym.tracking.evaluate import run_path

    cfg = load_scenario(scenario).with_overrides(parse_sets(sets, scenario))
    if len(cfg.task.path) < 2:
        raise InputError(f"{scenario}: task.path needs at least two waypoints to drive")
    run = run_path(cfg, seed, use_ego=ego, use_prior=prior)
    if plot:
        from lrp_gym.commands._common import save_figure
        from lrp_gym.tracking.plotting import plot_track_run
        from lrp_gym.world.world import World

        layout = World.from_config(cfg).layout
        s = run.summary
        title = f"tracked RMSE {s['tracked_rmse_m']:.3f} m, raw {s['raw_rmse_m']:.3f} m"
        save_figure(plot_track_run(run, layout.type_names, layout.type_index, title), plot)
    if json_out:
        print_json(run.summary)
        return
    if plot:
        console.print(f"saved {plot}")
    names = cfg.reflectors.layout
    table = Table(title=f"{cfg.name}: true / raw / tracked distance [m] per reflector")
    table.add_column("frame", justify="right")
    table.add_column("x, y [m]", justify="right")
    table.add_column("dets", justify="right")
    for i, r in enumerate(names):
        table.add_column(f"#{i} ({r.type})", justify="right")
    for k in range(len(run.trajectory)):
        x, y = run.trajectory.poses[k, :2]
        cells = [
            f"{run.truth_m[k, i]:.3f} / {_fmt(run.raw_m[k, i])} / "
            f"{_fmt(run.tracked_m[k, i], bool(run.tracked_fresh[k, i]))}"
            for i in range(len(names))
        ]
        table.add_row(str(k), f"{x:.2f}, {y:.2f}", str(len(run.detections[k])), *cells)
    console.print(table)
    s = run.summary
    console.print(
        f"frames {s['frames']}  raw RMSE {s['raw_rmse_m']:.4f} m  tracked RMSE "
        f"{s['tracked_rmse_m']:.4f} m  swaps {s['swaps']}  missed frames {s['missed_frames']}"
    )


def register(app: typer.Typer) -> None:
    app.command("track")(track)
