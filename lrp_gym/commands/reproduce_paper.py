"""``lrp-gym reproduce-paper``: the paper's positioning experiment (look-up table vs AMCL)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import typer

from lrp_gym.commands._cluster import check_ray_options, ray_option, resume_option
from lrp_gym.commands._common import (
    FIDELITIES,
    check_distinct,
    check_output,
    check_random_rooms,
    choice,
    console,
    err_console,
    fidelity_option,
    force_option,
    json_option,
    load_config,
    out_option,
    parse_sets,
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
from lrp_gym.commands._reproduce_plot import plot_errors
from lrp_gym.config import ScenarioConfig, deep_merge
from lrp_gym.errors import InputError
from lrp_gym.experiments.reproduce import PAPER, reproduce

ESTIMATORS = ("cluster", "best_k")


def reproduce_paper(
    scenario: str = scenario_argument(),
    runs: int = typer.Option(10, "--runs", metavar="N", help="Independent runs."),
    seed: int = seed_option("Root seed."),
    noise: bool = typer.Option(
        False, "--noise/--no-noise", help="Thermal noise in the radar (the paper: off)."
    ),
    fidelity: str = fidelity_option(),
    true_fingerprints: bool = typer.Option(
        False,
        "--true-fingerprints/--no-true-fingerprints",
        help="Feed the true distances to the look-up table and AMCL (bypass radar and tracker).",
    ),
    particles: int | None = typer.Option(
        None, "--particles", metavar="N", help="Override the initial (and most) particles."
    ),
    estimator: str = typer.Option(
        "cluster",
        "--estimator",
        metavar="cluster|best_k",
        help="AMCL pose estimate: cluster (heaviest cluster, the project default) or best_k "
        "(the paper's rule: 20 best particles within 15 cm of the best).",
    ),
    localizer: str = typer.Option(
        "amcl",
        "--localizer",
        metavar="amcl|grid",
        help="amcl, or grid: also run the histogram (Bayes yardstick) filter with AMCL's "
        "models on the same detections and odometry; slow.",
    ),
    sets: list[str] = sets_option(),
    ray: str | None = ray_option("the runs (with --random-rooms: the rooms), one a task,"),
    resume: bool = resume_option(),
    out: str | None = out_option("the results as JSON"),
    plot: str | None = plot_option("the error figure"),
    force: bool = force_option(),
    json_out: bool = json_option("the results"),
    random_rooms: int = typer.Option(
        0,
        "--random-rooms",
        metavar="N",
        help="Instead of the scenario: AMCL on N generated rooms (room seeds 0..N-1), with the "
        "radar chain and with true fingerprints (see docs/scenarios.md).",
    ),
) -> None:
    """Run the full chain (radar, CFAR, tracking, look-up table, AMCL) along the scenario's
    path and compare the per-position errors with the paper's."""
    out_path, plot_path = _check_options(
        runs, fidelity, estimator, localizer, particles, out, plot, force, random_rooms
    )
    study: dict[str, object] = dict(command="reproduce-paper", scenario=scenario, sets=sets)
    study |= dict(fidelity=fidelity)
    study |= dict(noise=noise, true_fingerprints=true_fingerprints, particles=particles)
    study |= dict(estimator=estimator, localizer=localizer, random_rooms=random_rooms)
    sidecar = check_ray_options(ray, resume, out_path, force, study | {"runs": runs, "seed": seed})
    run = None if ray is None else {"address": ray, "sidecar": sidecar, "resume": resume}
    if random_rooms:
        if true_fingerprints or plot_path:
            raise InputError("--random-rooms: runs both fingerprint kinds and draws no --plot")
        load_config(scenario, sets, fidelity)  # the rooms replace it, but bad input is an error
        rooms_over = deep_merge(parse_sets(sets, scenario), {"radar": {"noise": noise}})
        if particles is not None:
            rooms_over = deep_merge(rooms_over, _particles(particles, 200))
        if parse_sets(sets, scenario).get("localization", {}).get("method") == "grid":
            localizer = "grid"
        _random_rooms(
            random_rooms, runs, seed, rooms_over, estimator, out_path, json_out, localizer, run
        )
        return
    cfg = _scenario_config(scenario, sets, fidelity, noise, particles)
    if cfg.localization.method == "grid":  # --set localization.method=grid means the same
        localizer = "grid"
    result = reproduce(
        cfg,
        runs=runs,
        seed=seed,
        progress=_progress_printer(runs),
        true_fingerprints=true_fingerprints,
        estimator=estimator,
        localizer=localizer,
        runner=None if run is None else _runs_on_ray(run, _progress_printer(runs)),
    )
    data = result.to_dict() | {"noise": noise, "fidelity": cfg.radar.fidelity}
    if out_path is not None:
        write_json(data, out_path)
    if sidecar is not None:
        sidecar.remove()  # the result is whole: the partial results are no longer needed
    if plot_path is not None:
        noise_txt = "noise on" if noise else "noise off"
        save_figure(plot_errors(result, f"{cfg.name}, {noise_txt}, {estimator}"), plot_path)
    if json_out:
        print_json(data)
    else:
        _print(cfg.name, data, noise)
    for p in (out_path, plot_path):
        if p is not None:
            wrote(p, quiet=json_out)


def _check_options(
    runs: int,
    fidelity: str | None,
    estimator: str,
    localizer: str,
    particles: int | None,
    out: str | None,
    plot: str | None,
    force: bool,
    random_rooms: int,
) -> tuple[Path | None, Path | None]:
    """The --out and --plot paths, after checking every option (InputError naming it)."""
    if runs < 1:
        raise InputError(f"--runs: must be at least 1, got {runs}")
    choice(fidelity, FIDELITIES, "--fidelity")
    choice(estimator, ESTIMATORS, "--estimator")
    choice(localizer, ("amcl", "grid"), "--localizer")
    if particles is not None and particles < 10:
        raise InputError(f"--particles: must be at least 10, got {particles}")
    out_path = check_output(out, "--out", force, (".json",))
    plot_path = check_output(plot, "--plot", force, (".png", ".pdf", ".svg"))
    check_distinct(out_path, plot_path)
    check_random_rooms(random_rooms)
    return out_path, plot_path


def _scenario_config(
    scenario: str, sets: list[str], fidelity: str | None, noise: bool, particles: int | None
) -> ScenarioConfig:
    """The scenario with --set, --fidelity, --noise and --particles applied; it needs a path."""
    cfg = load_config(scenario, sets, fidelity)
    over: dict = {"radar": {"noise": noise}}
    if particles is not None:
        over.update(_particles(particles, cfg.localization.min_particles))
    cfg = cfg.with_overrides(over)
    if len(cfg.task.path) < 2:
        raise InputError(f"SCENARIO: {cfg.name} has no path (task.path needs 2+ waypoints)")
    return cfg


def _runs_on_ray(run: dict, progress: Callable[[int, dict], None]) -> Callable:
    """``reproduce``'s runner: the runs as Ray tasks (``run``: address, sidecar, resume),
    ``progress`` as each finishes."""
    from lrp_gym.experiments import reproduce as rp
    from lrp_gym.experiments.cluster import run_units

    def runner(task: Callable, units: list) -> list:
        index = {key: i for i, (key, _) in enumerate(units)}
        return run_units(
            task, units, encode=rp.run_to_json, decode=rp.run_from_json,
            on_result=lambda key, r: progress(index[key], rp.run_summary(r)), **run,
        )  # fmt: skip

    return runner


def _progress_printer(runs: int) -> Callable[[int, dict], None]:
    """A progress callback that prints each run's mean errors to stderr as it finishes."""

    def progress(run: int, info: dict) -> None:
        grid = info.get("grid_mean_error_m")
        err_console.print(
            f"run {run + 1}/{runs}: LUT mean error {info['lut_mean_error_m']:.3f} m, "
            f"AMCL mean error {info['amcl_mean_error_m']:.3f} m"
            + (f", grid mean error {grid:.3f} m" if grid is not None else ""),
            highlight=False,
        )

    return progress


def _print(name: str, data: dict, noise: bool) -> None:
    grid = data.get("grid")
    cols: tuple[str, ...] = ("pos", "LUT mean [m]", "AMCL mean [m]", "AMCL std [m]", "particles")
    if grid:
        cols += ("grid mean [m]", "grid std [m]")
    t = table(
        f"{name}: position errors (noise {'on' if noise else 'off'}, {data['runs']} runs)", cols
    )
    for i in range(data["positions"]):
        t.add_row(
            str(i + 1),
            f"{data['lut']['errors_m'][i]:.3f}",
            f"{data['amcl']['mean_errors_m'][i]:.3f}",
            f"{data['amcl']['std_errors_m'][i]:.3f}",
            f"{data['amcl']['mean_particles'][i]:.0f}",
            *(
                (f"{grid['mean_errors_m'][i]:.3f}", f"{grid['std_errors_m'][i]:.3f}")
                if grid
                else ()
            ),
        )
    console.print(t)
    if grid:
        conv_g = grid["converged_after"]
        console.print(
            f"grid filter mean error {grid['mean_error_m']:.3f} m, converged after "
            f"{conv_g if conv_g is not None else 'never'}",
            highlight=False,
        )
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
    n: int,
    runs: int,
    seed: int,
    over: dict,
    estimator: str,
    json_path,
    json_out: bool,
    localizer: str = "amcl",
    run: dict | None = None,
) -> None:
    """``--random-rooms``: the generated-room baseline, one line per room as it finishes
    (on stderr; with ``--json`` the summary goes to stdout as JSON instead of the table);
    ``run`` (address, sidecar, resume): one Ray task per room."""
    from lrp_gym.experiments.rooms import summary, sweep

    def progress(r) -> None:
        grid = "" if r.grid_radar_m is None else f", grid filter {r.grid_radar_m:.3f} m"
        err_console.print(
            f"room {r.seed}: {r.size_m[0]:.1f} x {r.size_m[1]:.1f} m, {r.obstacles} obstacles, "
            f"{r.reflectors} reflectors ({r.kinds}), {r.frames} frames: AMCL "
            f"{r.amcl_radar_m:.3f} m (true fingerprints {r.amcl_true_m:.3f} m){grid}",
            highlight=False,
        )

    if run is not None:
        results = _rooms_on_ray(n, runs, seed, over, estimator, localizer, run, progress)
    else:
        results = sweep(
            range(n),
            runs=runs,
            run_seed=seed,
            overrides=over,
            estimator=estimator,
            progress=progress,
            localizer=localizer,
        )
    data = summary(results)
    if json_path:
        write_json(data, json_path)
    if run is not None and run["sidecar"] is not None:
        run["sidecar"].remove()  # the result is whole: the partial results are no longer needed
    if json_out:
        print_json(data)
        if json_path:
            wrote(json_path, quiet=True)
        return
    _print_rooms(results, data, runs)
    if json_path:
        wrote(json_path)


def _rooms_on_ray(n, runs, seed, over, estimator, localizer, run, progress) -> list:
    """The generated rooms as Ray tasks, one room each (``run``: address, sidecar, resume)."""
    from dataclasses import asdict

    from lrp_gym.experiments.cluster import run_units
    from lrp_gym.experiments.rooms import RoomUnit, room_from_json, room_result

    units = [
        (f"room {s}", RoomUnit(s, runs, seed, over, estimator, False, localizer)) for s in range(n)
    ]
    return run_units(
        room_result, units, encode=asdict, decode=room_from_json,
        on_result=lambda _key, r: progress(r), **run,
    )  # fmt: skip


def _print_rooms(results: list, data: dict, runs: int) -> None:
    """The ``--random-rooms`` table: one row per generated room, then the medians."""
    t = table(
        f"AMCL mean error on {len(results)} generated rooms ({runs} runs each)",
        ("room", "size [m]", "obst.", "refl.", "kinds", "frames", "radar [m]", "true fp [m]"),
    )
    for r in results:
        t.add_row(
            str(r.seed),
            f"{r.size_m[0]:.1f} x {r.size_m[1]:.1f} x {r.size_m[2]:.1f}",
            str(r.obstacles),
            str(r.reflectors),
            r.kinds,
            str(r.frames),
            f"{r.amcl_radar_m:.3f}",
            f"{r.amcl_true_m:.3f}",
        )
    console.print(t)
    console.print(
        f"median AMCL mean error: {data['median_amcl_radar_m']:.3f} m with the radar chain, "
        f"{data['median_amcl_true_m']:.3f} m with true fingerprints",
        highlight=False,
    )


def register(app: typer.Typer) -> None:
    app.command("reproduce-paper", short_help="The paper's experiment: look-up table vs AMCL.")(
        reproduce_paper
    )
