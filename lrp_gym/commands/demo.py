"""``lrp-gym demo``: pure pursuit drives the scenario's path on the full radar chain."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

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

if TYPE_CHECKING:  # the env stack loads only when the command runs
    from lrp_gym.config import ScenarioConfig
    from lrp_gym.experiments.episodes import EpisodeResult
    from lrp_gym.world.world import World

DEMO_ENV = "LRPRadarNav-v0"
COLUMNS: tuple[str, ...] = ("step", "true x [m]", "true y [m]", "est x [m]", "est y [m]")
COLUMNS += ("error [m]", "std [m]", "dets", "conv")
#: metrics of :func:`~lrp_gym.experiments.episodes.summarize` the summary reports, in this order
SUMMARY_METRICS = (
    "mean_loc_error_m",
    "p95_loc_error_m",
    "max_loc_error_m",
    "time_localised",
    "mean_cross_track_m",
)


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
    folder = _check_options(steps, fidelity, out)
    over = overrides(scenario, sets, fidelity)
    result, infos, world, cfg = _run(scenario, over, steps, seed)
    summary = _summary(result, cfg, scenario)
    if not json_out:
        t = table(f"pure pursuit on {DEMO_ENV}, scenario {scenario}, seed {seed}", COLUMNS)
        for row in _rows(infos):
            t.add_row(*row)
        console.print(t)
        _print(summary)
    else:
        print_json(summary)
    _write(folder, summary, world, quiet=json_out)


def _run(scenario: str, over: dict, steps: int, seed: int):
    """Drive one episode of at most ``steps`` frames: result, step infos, world and config."""
    import gymnasium as gym

    import lrp_gym  # noqa: F401  (registers the env ids)
    from lrp_gym.experiments.episodes import nav_env

    env = gym.make(
        DEMO_ENV,
        scenario=scenario,
        overrides=over or None,
        task_mode="path",
        max_episode_steps=steps,
    )
    try:
        result, infos = _drive(env, seed)
        base = nav_env(env)
        return result, infos, base.world, base.cfg
    finally:
        env.close()


def _write(folder: Path, summary: dict[str, Any], world: World, quiet: bool) -> None:
    """trajectory.png (true and estimated tracks over the room) and summary.json."""
    from agents.plotting import save_trajectory

    title = (
        f"{'reached the goal' if summary['success'] else 'did not reach the goal'} in "
        f"{summary['steps']} frames, mean error {summary['mean_loc_error_m']:.3f} m"
    )
    png = save_trajectory(
        folder / "trajectory.png",
        world,
        summary["true_xy"],
        summary["est_xy"],
        summary["waypoints_m"],
        title,
    )
    wrote(png, quiet=quiet)
    wrote(write_json(summary, folder / "summary.json"), quiet=quiet)


def _check_options(steps: int, fidelity: str | None, out: Path) -> Path:
    """The run folder, after checking --steps, --fidelity and --out (InputError naming them)."""
    if steps < 1:
        raise InputError(f"--steps: must be at least 1, got {steps}")
    choice(fidelity, FIDELITIES, "--fidelity")
    folder = check_output(out, "--out", directory=True)
    if folder is None:
        raise InputError("--out: give a folder")
    for name in ("trajectory.png", "summary.json"):
        if (folder / name).is_dir():
            raise InputError(f"--out: {folder / name} is a folder, expected a file name")
    return folder


def _drive(env, seed: int) -> tuple[EpisodeResult, list[dict[str, Any]]]:
    """Run one pure-pursuit episode; its :class:`EpisodeResult` and the info of every step."""
    import gymnasium as gym

    from agents.pure_pursuit import PurePursuitPolicy
    from lrp_gym.experiments.episodes import run_episode

    class _InfoRecorder(gym.Wrapper):
        # The episode runner keeps only the metrics; the table also wants std and detections.
        def step(self, action):
            out = self.env.step(action)
            infos.append(out[-1])
            return out

    infos: list[dict[str, Any]] = []
    policy = PurePursuitPolicy.from_env(env)
    return run_episode(_InfoRecorder(env), policy, seed), infos


def _rows(infos: list[dict[str, Any]]) -> list[tuple[str, ...]]:
    """One table row per step: true and estimated position, error, spread, detections."""
    from lrp_gym.localization.metrics import LOCALISED_M

    rows = []
    for k, info in enumerate(infos, start=1):
        t, e, err = info["true_pose"], info["est_pose"], info["position_error_m"]
        colour = "green" if err < LOCALISED_M else "red"
        rows.append(
            (
                str(k),
                *(f"{v:.3f}" for v in (t[0], t[1], e[0], e[1])),
                f"[{colour}]{err:.3f}[/]",
                f"{max(info['pose_std'][:2]):.3f}",
                str(info["n_detections"]),
                "yes" if info["converged"] else "no",
            )
        )
    return rows


def _summary(result: EpisodeResult, cfg: ScenarioConfig, scenario: str) -> dict[str, Any]:
    """The demo's summary: the episode runner's metrics of this one episode, and its tracks."""
    from lrp_gym.experiments.episodes import summarize

    metrics = summarize([result])
    return {
        "env_id": DEMO_ENV,
        "scenario": scenario,
        "fidelity": cfg.radar.fidelity,
        "seed": result.seed,
        "steps": result.steps,
        "success": result.success,
        "collision": result.collision,
        # Frames driven, not time to goal: the demo also reports a run that misses the goal.
        "time_s": result.steps * cfg.task.frame_period_s,
        "driven_length_m": result.path_length_m,
        **{key: metrics[key] for key in SUMMARY_METRICS},
        "true_xy": result.true_xy,
        "est_xy": result.est_xy,
        "waypoints_m": result.waypoints_m,
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
