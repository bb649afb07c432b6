"""``lrp-gym sweep CONFIG``: Ray Tune over ``lrp-gym train`` trials (see :mod:`agents.sweep`)."""

from __future__ import annotations

import shutil
from pathlib import Path

import typer
from rich.console import Console

from lrp_gym.commands._cluster import RAY_LOCAL, check_ray_options
from lrp_gym.commands._common import (
    as_flags,
    check_output,
    console,
    force_option,
    json_option,
    print_json,
    table,
    write_json,
    wrote,
)
from lrp_gym.errors import InputError


def sweep(
    config: Path = typer.Argument(
        ...,
        metavar="CONFIG",
        help="Sweep YAML: PPO config and env, seeds, hyperparameter grid, steps per trial "
        "(e.g. configs/sweep-smoke.yaml).",
        show_default=False,
    ),
    ray: str = typer.Option(
        RAY_LOCAL,
        "--ray",
        metavar="[ADDRESS]",
        help="Where the trials run: local (default; a Ray started here with this machine's "
        "cores), auto or HOST:PORT joins a running cluster (pip install lrp-gym[cluster]).",
    ),
    out: Path = typer.Option(
        None,
        "--out",
        metavar="FOLDER",
        help="Sweep folder: Tune's state (tune/, one folder per trial with its run folder "
        "and last checkpoint) and sweep.json (default runs/sweep-<CONFIG name>).",
    ),
    resume: bool = typer.Option(
        False,
        "--resume",
        help="Complete the sweep in --out: unfinished and failed trials continue from their "
        "last checkpoint.",
    ),
    force: bool = force_option(),
    export: Path = typer.Option(
        None,
        "--export",
        metavar="FOLDER",
        help="After the sweep, ship the best trial's best model (+ statistics, + eval JSON) "
        "to this folder, as train --export does.",
    ),
    export_episodes: int = typer.Option(
        50,
        "--export-episodes",
        metavar="N",
        help="Episodes of the shipped model's final eval, on the sweep's env.",
    ),
    json_out: bool = json_option("the trials and the best one"),
) -> None:
    """Train PPO for every seed x hyperparameter combination of CONFIG as Ray Tune trials;
    each reports its evaluation as it trains, a lost trial resumes from its checkpoint, and
    the best (by the evaluation success) can be exported."""
    from agents import sweep as sw

    if export_episodes < 1:
        raise InputError(f"--export-episodes: must be at least 1, got {export_episodes}")
    spec = sw.load_sweep(config)
    out_dir = Path(out) if out is not None else Path("runs") / f"sweep-{Path(config).stem}"
    _check_folder(out_dir, resume, force)
    export_dir = check_output(export, "--export", directory=True)
    check_ray_options(ray, False, None, False, {})
    say = Console(stderr=True, highlight=False) if json_out else console
    say.print(f"{len(sw.trials(spec))} trials of {spec['timesteps']} steps on Ray ({ray})")
    with as_flags(address="--ray"):
        doc = sw.run_sweep(spec, out_dir, ray, resume)
    if export_dir is not None:
        from agents.ppo import export_model

        with as_flags(run_dir="--export"):
            doc["export"] = export_model(
                doc["best"]["checkpoint"],
                export_dir,
                eval_env_id=spec["env"],
                episodes=export_episodes,
            )
    summary = write_json(doc, out_dir / "sweep.json")
    _print(say, doc)
    if json_out:
        print_json(doc)
    wrote(summary, quiet=json_out)
    if export_dir is not None:
        for name in (doc["export"]["model"], doc["export"]["statistics"], "ppo_lrp_nav.json"):
            wrote(export_dir / name, quiet=json_out)


def _check_folder(out_dir: Path, resume: bool, force: bool) -> None:
    """An earlier sweep in ``out_dir`` is continued only with --resume, replaced with --force."""
    check_output(out_dir, "--out", directory=True)
    earlier = [out_dir / n for n in ("tune", "sweep.json") if (out_dir / n).exists()]
    if resume and force:
        raise InputError("--resume: cannot be combined with --force")
    if resume and not (out_dir / "tune").is_dir():
        raise InputError(f"--resume: no sweep to complete in {out_dir}")
    if earlier and not (resume or force):
        raise InputError(
            f"--out: {out_dir} holds an earlier sweep; complete it (--resume), replace it "
            "(--force) or choose another folder"
        )
    if force:
        for p in earlier:
            shutil.rmtree(p) if p.is_dir() else p.unlink()


def _print(say: Console, doc: dict) -> None:
    """One row per trial, the best one marked."""
    best = doc["best"]["path"]
    t = table(f"sweep ({doc['metric']} picks the best)", ("trial", "steps", "success", "return"))
    for row in doc["trials"]:
        params = ", ".join(f"{k}={v}" for k, v in row["params"].items())
        mark = " (best)" if row["path"] == best else ""
        succ = "-" if row["success_rate"] is None else f"{100 * row['success_rate']:.0f} %"
        ret = "-" if row["mean_reward"] is None else f"{row['mean_reward']:.2f}"
        t.add_row(
            params + mark + (" failed" if row["error"] else ""), str(row["timesteps"]), succ, ret
        )
    say.print(t)


def register(app: typer.Typer) -> None:
    app.command("sweep", short_help="Ray Tune over PPO training trials; export the best.")(sweep)
