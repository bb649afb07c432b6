"""``lrp-gym demo``: pure pursuit drives the scenario's path on the full radar chain."""

from __future__ import annotations

from pathlib import Path

import typer

from lrp_gym.commands._common import (
    FIDELITIES,
    check_output,
    choice,
    console,
    json_option,
    overrides,
    print_json,
    scenario_argument,
    seed_option,
    sets_option,
    table,
    write_json,
    wrote,
)
from lrp_gym.errors import InputError

DEMO_ENV = "LRPRadarNav-v0"
COLUMNS: tuple[str, ...] = ("step", "true x [m]", "true y [m]", "est x [m]", "est y [m]")
COLUMNS += ("error [m]", "std [m]", "dets", "conv")


def demo(
    scenario: str = scenario_argument(),
    steps: int = typer.Option(
        200, "--steps", metavar="N", help="Most frames to drive (the episode may end sooner)."
    ),
    seed: int = seed_option("Seed of the episode (radar noise, odometry, AMCL)."),
    fidelity: str | None = typer.Option(
        None,
        "--fidelity",
        metavar="signal|detections",
        help="Radar model (default: the scenario's radar.fidelity, signal for ipin2023).",
    ),
    sets: list[str] = sets_option(),
    out: Path = typer.Option(
        Path("outputs/demo"),
        "--out",
        metavar="FOLDER",
        help="Run folder: trajectory.png and summary.json are written (replaced) there.",
    ),
    json_out: bool = json_option("the summary"),
) -> None:
    """Drive SCENARIO's path with pure pursuit on the radar/AMCL estimate.

    Runs the radar (FMCW beat signal, FFT, CFAR at the signal fidelity), LRP tracking and AMCL
    every frame, prints true vs estimated position per step, and writes trajectory.png and
    summary.json into the --out folder.
    """
    if steps < 1:
        raise InputError(f"--steps: must be at least 1, got {steps}")
    choice(fidelity, FIDELITIES, "--fidelity")
    folder = check_output(out, "--out", directory=True)
    if folder is None:
        raise InputError("--out: give a folder")
    for name in ("trajectory.png", "summary.json"):
        if (folder / name).is_dir():
            raise InputError(f"--out: {folder / name} is a folder, expected a file name")
    over = overrides(scenario, sets, fidelity)
    import gymnasium as gym

    import lrp_gym  # noqa: F401  (registers the env ids)
    from agents.plotting import save_trajectory
    from lrp_gym.experiments.episodes import nav_env

    env = gym.make(
        DEMO_ENV,
        scenario=scenario,
        overrides=over or None,
        task_mode="path",
        max_episode_steps=steps,
    )
    try:
        rows, tracks, info = _drive(env, seed)
        base = nav_env(env)
        summary = _summary(base, scenario, seed, tracks, info)
    finally:
        env.close()
    if not json_out:
        t = table(f"pure pursuit on {DEMO_ENV}, scenario {scenario}, seed {seed}", COLUMNS)
        for row in rows:
            t.add_row(*row)
        console.print(t)
        _print(summary)
    else:
        print_json(summary)
    n = summary["steps"]
    title = (
        f"{'reached the goal' if summary['success'] else 'did not reach the goal'} in "
        f"{n} frames, mean error {summary['mean_loc_error_m']:.3f} m"
    )
    waypoints_m = summary["waypoints_m"]
    png = save_trajectory(
        folder / "trajectory.png", base.world, tracks[0], tracks[1], waypoints_m, title
    )
    wrote(png, quiet=json_out)
    wrote(write_json(summary, folder / "summary.json"), quiet=json_out)


def _drive(env, seed: int):
    """Run one episode; per-step table rows, (true, estimated) xy arrays and the last info."""
    import numpy as np

    from agents.pure_pursuit import PurePursuitPolicy
    from lrp_gym.localization.metrics import LOCALISED_M

    policy = PurePursuitPolicy.from_env(env)
    obs, info = env.reset(seed=seed)
    true_xy, est_xy = [info["true_pose"][:2]], [info["est_pose"][:2]]
    rows: list[tuple[str, ...]] = []
    errors: list[float] = []
    done = False
    while not done:
        action, _ = policy.predict(obs)
        obs, _, terminated, truncated, info = env.step(action)
        done = terminated or truncated
        t, e, err = info["true_pose"], info["est_pose"], info["position_error_m"]
        true_xy.append(t[:2])
        est_xy.append(e[:2])
        errors.append(err)
        colour = "green" if err < LOCALISED_M else "red"
        rows.append(
            (
                str(len(rows) + 1),
                *(f"{v:.3f}" for v in (t[0], t[1], e[0], e[1])),
                f"[{colour}]{err:.3f}[/]",
                f"{max(info['pose_std'][:2]):.3f}",
                str(info["n_detections"]),
                "yes" if info["converged"] else "no",
            )
        )
    return rows, (np.asarray(true_xy), np.asarray(est_xy), np.asarray(errors)), info


def _summary(base, scenario: str, seed: int, tracks, info) -> dict:
    import numpy as np

    from lrp_gym.experiments.episodes import cross_track_m
    from lrp_gym.localization.metrics import LOCALISED_M

    true_xy, est_xy, err = tracks
    n = len(err)
    waypoints = base.path.waypoints_m
    return {
        "env_id": DEMO_ENV,
        "scenario": scenario,
        "fidelity": base.cfg.radar.fidelity,
        "seed": seed,
        "steps": n,
        "success": bool(info["is_success"]),
        "collision": bool(info["collision"]),
        "time_s": n * base.cfg.task.frame_period_s,
        "driven_length_m": float(np.sum(np.linalg.norm(np.diff(true_xy, axis=0), axis=1))),
        "mean_loc_error_m": float(err.mean()),
        "p95_loc_error_m": float(np.percentile(err, 95)),
        "max_loc_error_m": float(err.max()),
        "time_localised": float(np.mean(err < LOCALISED_M)),
        "mean_cross_track_m": float(cross_track_m(true_xy[1:], waypoints).mean()),
        "true_xy": true_xy,
        "est_xy": est_xy,
        "waypoints_m": waypoints,
    }


def _print(s: dict) -> None:
    state = "[green]goal reached[/]" if s["success"] else "[red]goal not reached[/]"
    console.print(
        f"{state} after {s['steps']} frames ({s['time_s']:.2f} s); localisation error mean "
        f"{s['mean_loc_error_m']:.3f} m, p95 {s['p95_loc_error_m']:.3f} m, "
        f"max {s['max_loc_error_m']:.3f} m; localised {100 * s['time_localised']:.0f} % "
        f"of the time"
    )


def register(app: typer.Typer) -> None:
    app.command("demo", short_help="Pure pursuit drives the path on the radar/AMCL estimate.")(demo)
