"""``lrp-gym track``: drive the scenario path through the radar and the LRP tracker."""

from __future__ import annotations

import numpy as np
import typer

from lrp_gym.commands._common import (
    FIDELITIES,
    check_distinct,
    check_output,
    choice,
    console,
    fidelity_option,
    force_option,
    json_option,
    load_config,
    out_option,
    plot_option,
    print_json,
    save_figure,
    scenario_argument,
    seed_option,
    sets_option,
    table,
    write_json,
    wrote,
)
from lrp_gym.errors import InputError


def _fmt(x: float, fresh: bool = True) -> str:
    if not np.isfinite(x):
        return "[dim]-[/]"
    return f"{x:.3f}" if fresh else f"[yellow]{x:.3f}*[/]"


def track(
    scenario: str = scenario_argument(),
    seed: int = seed_option("Seed of the radar noise."),
    fidelity: str | None = fidelity_option(),
    sets: list[str] = sets_option(),
    prior: bool = typer.Option(
        True,
        "--prior/--no-prior",
        help="Identify the reflectors with AMCL's last estimate moved by the odometry.",
    ),
    ego: bool = typer.Option(
        True,
        "--ego/--no-ego",
        help="Predict static points from the odometry (else the paper's constant-velocity model).",
    ),
    out: str | None = out_option("the summary as JSON"),
    plot: str | None = plot_option("true, detected and tracked distances per reflector"),
    force: bool = force_option(),
    json_out: bool = json_option("the summary"),
) -> None:
    """Drive SCENARIO's task.path through the radar chain and the tracker.

    Prints, per frame and reflector, the true distance, the matched RCS-gated detection (raw)
    and the tracked distance (* = coasting or not yet confirmed), then the RMSEs, the frames
    with a track swap and the frames where some reflector had no fresh tracked distance. AMCL
    runs alongside on the gated detections, as in the env; its estimate is the prior.
    """
    from lrp_gym.experiments.track_path import run_path

    choice(fidelity, FIDELITIES, "--fidelity")
    out_path = check_output(out, "--out", force, (".json",))
    plot_path = check_output(plot, "--plot", force, (".png", ".pdf", ".svg"))
    check_distinct(out_path, plot_path)
    cfg = load_config(scenario, sets, fidelity)
    if len(cfg.task.path) < 2:
        raise InputError(f"SCENARIO: {scenario}: task.path needs at least two waypoints to drive")
    run = run_path(cfg, seed, use_ego=ego, use_prior=prior)
    if plot_path is not None:
        from lrp_gym.tracking.plotting import plot_track_run
        from lrp_gym.world.world import World

        layout = World.from_config(cfg).layout
        s = run.summary
        title = f"tracked RMSE {s['tracked_rmse_m']:.3f} m, raw {s['raw_rmse_m']:.3f} m"
        save_figure(plot_track_run(run, layout.type_names, layout.type_index, title), plot_path)
    if out_path is not None:
        write_json(run.summary, out_path)
    if json_out:
        print_json(run.summary)
    else:
        _print(cfg, run)
    for p in (plot_path, out_path):
        if p is not None:
            wrote(p, quiet=json_out)


def _print(cfg, run) -> None:
    names = cfg.reflectors.layout
    cols = ["frame", "x, y [m]", "dets", *(f"#{i} ({r.type})" for i, r in enumerate(names))]
    t = table(f"{cfg.name}: true / raw / tracked distance [m] per reflector", cols)
    for k in range(len(run.trajectory)):
        x, y = run.trajectory.poses[k, :2]
        cells = [
            f"{run.truth_m[k, i]:.3f} / {_fmt(run.raw_m[k, i])} / "
            f"{_fmt(run.tracked_m[k, i], bool(run.tracked_fresh[k, i]))}"
            for i in range(len(names))
        ]
        t.add_row(str(k), f"{x:.2f}, {y:.2f}", str(len(run.detections[k])), *cells)
    console.print(t)
    s = run.summary
    console.print(
        f"frames {s['frames']}  raw RMSE {s['raw_rmse_m']:.4f} m  tracked RMSE "
        f"{s['tracked_rmse_m']:.4f} m  swaps {s['swaps']}  missed frames {s['missed_frames']}"
    )


def register(app: typer.Typer) -> None:
    app.command("track", short_help="Drive the path through the radar chain and the tracker.")(
        track
    )
