"""``lrp-gym demo``: pure pursuit drives the paper's path on the full radar chain."""

from __future__ import annotations

from pathlib import Path

import typer

from lrp_gym.commands._common import console, write_json
from lrp_gym.errors import InputError

DEMO_ENV = "LRPRadarNav-v0"
DEMO_SCENARIO = "ipin2023"


def demo(
    steps: int = typer.Option(
        200, "--steps", help="Most frames to drive (the episode may end sooner)."
    ),
    out: Path = typer.Option(
        Path("outputs/demo"), "--out", help="Folder for the plot and the summary JSON."
    ),
    seed: int = typer.Option(
        0, "--seed", help="Seed of the episode (radar noise, odometry, AMCL)."
    ),
) -> None:
    """Drive the paper's 15-waypoint path with pure pursuit on the radar/AMCL estimate.

    Runs the signal-level radar (FMCW beat signal, FFT, CFAR), LRP tracking and AMCL every
    frame, prints true vs estimated position per step, and writes ``trajectory.png`` and
    ``summary.json`` into ``--out``.
    """
    if steps < 1:
        raise InputError(f"--steps: must be at least 1, got {steps}")
    import gymnasium as gym
    import numpy as np
    from rich.table import Table

    import lrp_gym  # noqa: F401  (registers the env ids)
    from agents.evaluate import LOCALISED_M, cross_track_m
    from agents.plotting import save_trajectory
    from agents.pure_pursuit import PurePursuitPolicy

    env = gym.make(DEMO_ENV, scenario=DEMO_SCENARIO, max_episode_steps=steps)
    policy = PurePursuitPolicy.from_env(env)
    obs, info = env.reset(seed=seed)
    base = env.unwrapped
    table = Table(title=f"pure pursuit on {DEMO_ENV}, scenario {DEMO_SCENARIO}, seed {seed}")
    for col in (
        "step",
        "true x",
        "true y",
        "est x",
        "est y",
        "error [m]",
        "std [m]",
        "dets",
        "conv",
    ):
        table.add_column(col, justify="right")
    true_xy, est_xy, errors = [info["true_pose"][:2]], [info["est_pose"][:2]], []
    done, n = False, 0
    while not done:
        action, _ = policy.predict(obs)
        obs, _, terminated, truncated, info = env.step(action)
        done = terminated or truncated
        n += 1
        t, e, err = info["true_pose"], info["est_pose"], info["position_error_m"]
        true_xy.append(t[:2])
        est_xy.append(e[:2])
        errors.append(err)
        colour = "green" if err < LOCALISED_M else "red"
        table.add_row(
            str(n),
            f"{t[0]:.3f}",
            f"{t[1]:.3f}",
            f"{e[0]:.3f}",
            f"{e[1]:.3f}",
            f"[{colour}]{err:.3f}[/]",
            f"{max(info['pose_std'][:2]):.3f}",
            str(info["n_detections"]),
            "yes" if info["converged"] else "no",
        )
    console.print(table)
    true_xy, est_xy, err = np.asarray(true_xy), np.asarray(est_xy), np.asarray(errors)
    waypoints = base.path.waypoints_m
    summary = {
        "env_id": DEMO_ENV,
        "scenario": DEMO_SCENARIO,
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
    out.mkdir(parents=True, exist_ok=True)
    title = (
        f"{'reached the goal' if summary['success'] else 'did not reach the goal'} in "
        f"{n} frames, mean error {summary['mean_loc_error_m']:.3f} m"
    )
    png = save_trajectory(out / "trajectory.png", base.world, true_xy, est_xy, waypoints, title)
    js = write_json(summary, out / "summary.json")
    env.close()
    state = "[green]goal reached[/]" if summary["success"] else "[red]goal not reached[/]"
    console.print(
        f"{state} after {n} frames ({summary['time_s']:.2f} s); localisation error mean "
        f"{summary['mean_loc_error_m']:.3f} m, p95 {summary['p95_loc_error_m']:.3f} m, "
        f"max {summary['max_loc_error_m']:.3f} m; localised {100 * summary['time_localised']:.0f} % "
        f"of the time"
    )
    console.print(f"wrote {png} and {js}")


def register(app: typer.Typer) -> None:
    app.command("demo")(demo)
