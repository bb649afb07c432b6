"""``lrp-gym robustness``: perturbation x severity matrix (see :mod:`lrp_gym.experiments.robustness`)."""

from __future__ import annotations

from pathlib import Path

import typer
from rich import box

from lrp_gym.commands._cluster import (
    PolicyFactory,
    check_ray_options,
    ray_option,
    reject_random_agent,
    resume_option,
)
from lrp_gym.commands._common import (
    FIDELITIES,
    as_flags,
    check_distinct,
    check_output,
    choice,
    console,
    fidelity_option,
    force_option,
    json_option,
    out_option,
    overrides,
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
from lrp_gym.commands.evaluate import (
    agent_option,
    agent_settings,
    agent_settings_option,
    check_agent,
    check_num_envs,
    env_option,
    episodes_option,
    model_option,
    num_envs_option,
    task_option,
)
from lrp_gym.errors import InputError

#: = ``lrp_gym.experiments.robustness.DEFAULT_EPISODES`` (the experiment is imported lazily so
#: ``lrp-gym --help`` stays fast; a test keeps the two equal).
DEFAULT_EPISODES = 50
BASELINE = "none"


def _floats(text: str, flag: str) -> list[float]:
    try:
        out = [float(t) for t in text.replace(",", " ").split()]
    except ValueError:
        raise InputError(f"{flag}: expected numbers separated by commas, got {text!r}") from None
    if not out:
        raise InputError(f"{flag}: give at least one value")
    return out


def robustness(
    scenario: str = scenario_argument(),
    agent: str = agent_option(),
    agent_options: list[str] = agent_settings_option(),
    model: Path = model_option(),
    env: str = env_option(),
    task: str = task_option(),
    fidelity: str = fidelity_option(),
    sets: list[str] = sets_option(),
    episodes: int = episodes_option("Episodes per cell", DEFAULT_EPISODES),
    severities: str = typer.Option(
        "0.25,0.5,1", "--severities", metavar="S,S,...", help="Severities in [0, 1], by commas."
    ),
    perturbations: str = typer.Option(
        None,
        "--perturbations",
        metavar="NAME,...",
        help="Perturbation names, by commas (default: all).",
    ),
    seed: int = seed_option("Seed of the first episode of every cell."),
    num_envs: int = num_envs_option(),
    ray: str = ray_option("each cell's episodes, 5 seeds a task,"),
    resume: bool = resume_option(),
    out: Path = out_option("the matrix as JSON"),
    plot: Path = plot_option("heat maps (success, time localised; value and 95 % interval)"),
    force: bool = force_option(),
    json_out: bool = json_option("the matrix"),
) -> None:
    """Closed-loop robustness: success, localisation error and kidnap recovery per
    perturbation x severity (first row: no perturbation)."""
    from lrp_gym.experiments import robustness as rb

    sev = _floats(severities, "--severities")
    names = (
        [t.strip() for t in perturbations.split(",") if t.strip()]
        if perturbations is not None
        else list(rb.PERTURBATION_NAMES)
    )
    for n in names:
        choice(n, rb.PERTURBATION_NAMES, "--perturbations")
    check_agent(agent, model, task, episodes)
    settings = agent_settings(agent, agent_options)
    check_num_envs(num_envs)
    with as_flags(
        perturbations="--perturbations", severities="--severities", episodes="--episodes"
    ):
        rb._check(names, sev, episodes)
    choice(fidelity, FIDELITIES, "--fidelity")
    if seed < 0:
        raise InputError(f"--seed: must be non-negative, got {seed}")
    reject_random_agent(agent, ray)
    out_path = check_output(out, "--out", force, (".json",))
    plot_path = check_output(plot, "--plot", force, (".png", ".pdf", ".svg"))
    check_distinct(out_path, plot_path)
    over = overrides(scenario, sets, fidelity)
    study = dict(command="robustness", agent=agent, model=model, env=env, task=task)
    study |= {"agent_options": settings} if settings else {}
    study |= dict(scenario=scenario, overrides=over, perturbations=names, severities=sev)
    sidecar = check_ray_options(ray, resume, out_path, force, study | {"seed": seed})
    run = None if ray is None else {"address": ray, "sidecar": sidecar, "resume": resume}
    with as_flags(env_id="--env", model_path="--model", agent="--agent", task="--task"):
        result = _run(
            rb, PolicyFactory(agent, model, seed, settings), agent, env, names, sev, episodes,
            seed, task, scenario, json_out, over, num_envs, run,
        )  # fmt: skip
    result["agent_options"] = settings  # as evaluate writes it, {} without --agent-option
    if plot_path is not None:
        save_figure(rb.plot_matrix(result), plot_path)
    if out_path is not None:
        write_json(result, out_path)
    if sidecar is not None:
        sidecar.remove()  # the result is whole: the partial results are no longer needed
    if json_out:
        print_json(result)
    else:
        _print(result, rb.RECOVERY_BUDGET_FRAMES)
    for p in (out_path, plot_path):
        if p is not None:
            wrote(p, quiet=json_out)


def _run(
    rb, policy, agent, env, names, sev, episodes, seed, task, scenario, quiet, over, num_envs, run
) -> dict:
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    total = episodes * (1 + len(names) * len(sev))
    with Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=Console(stderr=True),
        transient=quiet,
    ) as bar:
        job = bar.add_task("robustness", total=total)
        if run is not None:
            from lrp_gym.experiments.distributed import run_matrix_units

            bar.update(job, description=f"{'robustness on Ray':<26}")
            result = run_matrix_units(
                policy, agent, env, names, sev, episodes, seed, task, over, scenario, num_envs,
                on_result=lambda _key, part: bar.advance(job, len(part)), **run,
            )  # fmt: skip
        else:
            result = rb.run_matrix(
                policy,
                agent,
                env,
                names,
                sev,
                episodes,
                seed,
                task,
                overrides=over,
                progress=lambda label: bar.update(job, description=f"{label:<26}"),
                on_episode=lambda: bar.advance(job),
                scenario=scenario,
                num_envs=num_envs,
            )
    result["env_id"] = env or ("LRPRadarNavOracle-v0" if agent == "oracle" else "LRPRadarNav-v0")
    result["fidelity"] = (over.get("radar") or {}).get("fidelity")
    result["sets"] = over
    return result


def _cell(v: float | None, ci: list[float] | None, fmt) -> str:
    """The value, and below it its 95 % interval ``lo-hi`` (one number when both ends agree)."""
    if v is None:
        return "-"
    if ci is None:
        return fmt(v)
    lo, hi = fmt(ci[0]), fmt(ci[1])
    return f"{fmt(v)}\n{lo if lo == hi else f'{lo}-{hi}'}"


def _pct(v: float | None, ci: list[float] | None) -> str:
    """A share in percent."""
    return _cell(v, ci, lambda x: f"{100 * x:.0f}")


def _cm(v: float | None, ci: list[float] | None) -> str:
    """A length in metres shown in centimetres (one decimal below 10 cm)."""
    return _cell(v, ci, lambda x: f"{100 * x:.1f}" if 100 * x < 9.95 else f"{100 * x:.0f}")


def _frames(v: float | None, ci: list[float] | None) -> str:
    """Frames, rounded to whole ones (a median of an even count ends in .5; the JSON keeps it)."""
    return _cell(v, ci, lambda x: f"{x:.0f}")


def _print(result: dict, budget: int) -> None:
    from lrp_gym.experiments.robustness import SUSPECT_BUDGET_FRAMES

    e, s = result["episodes"], result["seed"]
    # Each cell: the value over its 95 % interval. Two-line headers, no vertical rules, lengths
    # in cm, the severity under the name: the nine columns fit 80 columns unfolded (p50 is in
    # the JSON).
    cols: tuple[str, ...] = ("perturbation\n  severity", "succ.\n[%]", "coll.\n[%]", "p95\n[cm]")
    cols += ("loc.\n[%]", "wrong\n[%]", "t.loc\n[fr.]", "recov.\n[fr.]", f"<= {budget}\n[%]")
    t = table(
        f"{result['agent']} on {result['env_id']} ({result['scenario']}, "
        f"{result['task'] or 'its task'}), {e} episodes/cell, seeds {s}..{s + e - 1}",
        cols,
        left=1,
    )
    t.box, t.padding, t.pad_edge = box.SIMPLE_HEAD, (0, 0), False
    for col in t.columns:  # names (missed_detections) and intervals stay whole
        col.no_wrap = True
    for c in result["cells"]:
        ci = c.get("ci95") or {}
        t.add_row(
            c["perturbation"] + ("" if c["perturbation"] == BASELINE else f"\n  {c['severity']:g}"),
            _pct(c["success_rate"], ci.get("success_rate")),
            _pct(c["collision_rate"], ci.get("collision_rate")),
            _cm(c["p95_loc_error_m"], ci.get("p95_loc_error_m")),
            _pct(c["time_localised"], ci.get("time_localised")),
            _pct(c.get("confidently_wrong_rate"), ci.get("confidently_wrong_rate")),
            _frames(c.get("median_frames_to_localised"), ci.get("median_frames_to_localised")),
            _frames(c["recovery_frames"], ci.get("recovery_frames")),
            _pct(c["recovered_within_budget"], ci.get("recovered_within_budget")),
        )
    console.print(t)
    console.print(
        "Each cell: value, and below it the 95 % interval (Wilson for succ., coll. and "
        f"<= {budget}; bootstrap over episodes for the rest). p95: localisation error; loc.: "
        "steps within 0.2 m; wrong: converged steps off by > 0.3 m; t.loc: median frames "
        "to first localised; recov.: median frames to recover after a kidnap; "
        f"<= {budget}: kidnaps recovered within {budget} frames.",
        highlight=False,
    )
    _print_stuck(result["cells"])
    for c in result["cells"]:
        if c.get("suspect_named_within_budget") is None:
            continue
        lo, hi = (c.get("ci95") or {}).get("suspect_named_within_budget") or (0.0, 1.0)
        console.print(
            f"{c['perturbation']} {c['severity']:g}: the moved or vanished reflector named "
            f"within {SUSPECT_BUDGET_FRAMES} frames in {100 * c['suspect_named_within_budget']:.0f} "
            f"% of episodes ({100 * lo:.0f}-{100 * hi:.0f} %); another one named in "
            f"{100 * c['false_suspect_rate']:.0f} %",
            highlight=False,
        )


def _print_stuck(cells: list[dict]) -> None:
    """Per cell, the share of episodes stuck on a wrong pose: a per-episode view of ``wrong``,
    which a few long stuck episodes dominate (cells without the key, from older JSON, are
    left out)."""
    from lrp_gym.localization.metrics import CONFIDENTLY_WRONG_M, STUCK_WRONG_FRAMES

    parts = []
    for c in cells:
        if c.get("stuck_wrong_rate") is None:
            continue
        lo, hi = (c.get("ci95") or {}).get("stuck_wrong_rate") or (0.0, 1.0)
        name = c["perturbation"] + ("" if c["perturbation"] == BASELINE else f" {c['severity']:g}")
        parts.append(f"{name} {100 * c['stuck_wrong_rate']:.0f} % ({100 * lo:.0f}-{100 * hi:.0f})")
    if parts:
        console.print(
            f"Episodes stuck (converged and off by > {CONFIDENTLY_WRONG_M:g} m for >= "
            f"{STUCK_WRONG_FRAMES} frames in a row): " + "; ".join(parts),
            highlight=False,
        )


def register(app: typer.Typer) -> None:
    app.command("robustness", short_help="Perturbation x severity matrix, closed loop.")(robustness)
