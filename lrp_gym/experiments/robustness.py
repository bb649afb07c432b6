"""Robustness matrix: perturbation x severity, closed-loop episodes on fixed seeds per cell.

Every cell runs ``episodes`` episodes on seeds ``seed .. seed + episodes - 1`` with the
runner of :mod:`lrp_gym.experiments.episodes` (same policy, same env id, same scenario; only the
``perturbations`` override differs), plus one baseline row without perturbation. Per cell:
success rate, collision rate, localisation error percentiles (p50, p95, pooled over all steps),
the share of steps localised (error < :data:`LOCALISED_M`), the trust metrics of
:mod:`lrp_gym.localization.metrics` (confidently wrong share, median frames to localise) and,
for ``kidnapping``, the frames AMCL needs to get back within :data:`LOCALISED_M` of the truth
after the jump. Every number comes with a 95 % interval (``ci95``; see
:mod:`lrp_gym.experiments.intervals`).

Default setting: the fast (detections-level) env ``LRPRadarNavFast-v0`` on the paper scenario
in path mode (``ipin2023``: its 15-waypoint path, the same start every episode; seeds change
sensor noise and the perturbations' draws). ``task="goal"`` uses sampled start/goal pairs.
The patrol scenarios (``ipin2023-patrol``, ``ipin2023-2types-patrol``: a closed loop driven six
times, about 170 frames) leave room after a once-only perturbation such as a kidnap.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from lrp_gym.config import PerturbationsConfig, deep_merge
from lrp_gym.experiments.episodes import (
    EpisodeResult,
    Policy,
    episode_results,
    make_eval_env,
    summarize,
)
from lrp_gym.experiments.intervals import (
    bootstrap_interval,
    median_of,
    pooled_percentile,
    pooled_share,
    wilson_interval,
)
from lrp_gym.localization import metrics
from lrp_gym.localization.metrics import CONFIDENTLY_WRONG_M, frames_to_localised

LOCALISED_M = metrics.LOCALISED_M
RECOVERY_BUDGET_FRAMES = 15
#: Frames within which a moved or vanished reflector should be named a suspect.
SUSPECT_BUDGET_FRAMES = 40
DEFAULT_ENV = "LRPRadarNavFast-v0"
DEFAULT_SEVERITIES = (0.25, 0.5, 1.0)
#: Episodes per cell by default: a 95 % Wilson interval at 100 % success is then 93-100 %.
DEFAULT_EPISODES = 50
PERTURBATION_NAMES = tuple(PerturbationsConfig.model_fields)
BASELINE = "none"


def recovery_frames(loc_error_m: np.ndarray, kidnap_frame: int, threshold_m: float = LOCALISED_M):
    """Frames after the kidnap frame until the error is below ``threshold_m`` again.

    ``loc_error_m[k - 1]`` is the error after step ``k`` (frame ``k``). 0 means the estimate
    was already within the threshold in the kidnap frame itself; None means it never came
    back before the episode ended (censored).
    """
    after = np.asarray(loc_error_m)[kidnap_frame - 1 :]
    hit = np.flatnonzero(after < threshold_m)
    return int(hit[0]) if hit.size else None


def cell_overrides(name: str, severity: float) -> dict[str, Any]:
    """The env override for one cell (empty for the baseline)."""
    return {} if name == BASELINE else {"perturbations": {name: {"severity": float(severity)}}}


def _check(perturbations: Sequence[str], severities: Sequence[float], episodes: int) -> None:
    unknown = [p for p in perturbations if p not in PERTURBATION_NAMES]
    if unknown:
        raise ValueError(
            f"perturbations: unknown {', '.join(map(repr, unknown))}; "
            f"choose from {', '.join(PERTURBATION_NAMES)}"
        )
    if not perturbations:
        raise ValueError("perturbations: give at least one")
    bad = [s for s in severities if not (np.isfinite(s) and 0.0 <= s <= 1.0)]
    if bad or not severities:
        raise ValueError(f"severities: each must be in [0, 1], got {list(severities)}")
    if episodes < 1:
        raise ValueError(f"episodes: must be at least 1, got {episodes}")


def run_cell(
    env: gym.Env,
    policy: Policy,
    name: str,
    severity: float,
    episodes: int,
    seed: int,
    on_episode: Callable[[], None] | None = None,
    rng: np.random.Generator | None = None,
    num_envs: int = 1,
) -> dict[str, Any]:
    """Run one cell's episodes in ``env`` (already built with the cell's overrides).

    ``rng`` draws the bootstrap resamples of the intervals (default: seeded with ``seed``);
    ``num_envs`` > 1 drives that many robots at once (the same episodes).
    """
    seeds = list(range(seed, seed + episodes))
    results = episode_results(
        env, policy, seeds, num_envs, None if on_episode is None else lambda _: on_episode()
    )
    return cell_from_results(name, severity, results, seed, rng)


def cell_from_results(
    name: str,
    severity: float,
    results: Sequence[EpisodeResult],
    seed: int,
    rng: np.random.Generator | None = None,
) -> dict[str, Any]:
    """One cell's numbers from its episodes in seed order (the bootstrap seeded with ``seed``
    unless ``rng`` is given): what :func:`run_cell` returns, wherever the episodes ran."""
    recov: list[int | None] = [
        recovery_frames(r.loc_error_m, r.kidnap_frame)
        for r in results
        if r.kidnap_frame is not None
    ]
    rng = np.random.default_rng(seed) if rng is None else rng
    return cell_statistics(name, severity, results, recov, rng)


def suspect_counts(results: Sequence[EpisodeResult]) -> tuple[int, int, int]:
    """The reflector monitor's score: (episodes naming a moved or vanished reflector within
    :data:`SUSPECT_BUDGET_FRAMES` of the perturbation's start, episodes with such a
    reflector, episodes naming another)."""
    perturbed = [r for r in results if r.perturbed_reflectors]
    named = sum(_named_in_budget(r) for r in perturbed)
    others = sum(bool(set(r.suspect_first_frame) - set(r.perturbed_reflectors)) for r in results)
    return named, len(perturbed), others


def _named_in_budget(r: EpisodeResult) -> bool:
    """Whether a perturbed reflector was named within the budget after it was perturbed (a
    hidden one counts from the frame it disappeared, not from the episode's start)."""
    after = r.perturbed_after_frame or (0,) * len(r.perturbed_reflectors)
    first = r.suspect_first_frame
    return any(
        first.get(j, np.inf) - k <= SUSPECT_BUDGET_FRAMES
        for j, k in zip(r.perturbed_reflectors, after, strict=True)
    )


def _suspect_statistics(results: Sequence[EpisodeResult]) -> tuple[dict, dict]:
    """The cell's reflector-monitor rates and their Wilson intervals."""
    named, n_perturbed, others = suspect_counts(results)
    n = len(results)
    values = {
        "suspect_named_within_budget": named / n_perturbed if n_perturbed else None,
        "false_suspect_rate": others / n,
    }
    ci = {
        "suspect_named_within_budget": wilson_interval(named, n_perturbed) if n_perturbed else None,
        "false_suspect_rate": wilson_interval(others, n),
    }
    return values, ci


def cell_statistics(
    name: str,
    severity: float,
    results: Sequence[EpisodeResult],
    recov: Sequence[int | None],
    rng: np.random.Generator,
) -> dict[str, Any]:
    """One cell's numbers and their 95 % intervals (``ci95``, same keys): Wilson for rates
    over episodes; for statistics pooled over steps and per-episode medians a percentile
    bootstrap over whole episodes (steps of one episode are correlated)."""
    n = len(results)
    s = summarize(list(results))
    errs = [r.loc_error_m for r in results]
    err = np.concatenate(errs)
    kidnapped = len(recov)
    within = sum(r is not None and r <= RECOVERY_BUDGET_FRAMES for r in recov)
    done = [r for r in recov if r is not None]
    # Per episode: frames to first localised (never: its length) and its converged errors.
    first = [frames_to_localised(e) for e in errs]
    to_loc = [len(e) if f is None else f for f, e in zip(first, errs)]
    wrong = [r.loc_error_m[r.converged] > CONFIDENTLY_WRONG_M for r in results]
    n_succ = sum(bool(r.success) for r in results)
    n_coll = sum(bool(r.collision) for r in results)
    suspects, suspects_ci = _suspect_statistics(results)

    def boot(items, stat):  # over whole episodes: the steps of one are correlated
        return bootstrap_interval(items, stat, rng)

    ci = {
        "success_rate": wilson_interval(n_succ, n),
        "collision_rate": wilson_interval(n_coll, n),
        "p50_loc_error_m": boot(errs, pooled_percentile(50)),
        "p95_loc_error_m": boot(errs, pooled_percentile(95)),
        "time_localised": boot([e < LOCALISED_M for e in errs], pooled_share),
        "confidently_wrong_rate": boot(wrong, pooled_share),
        "stuck_wrong_rate": wilson_interval(round(s["stuck_wrong_rate"] * n), n),
        "median_frames_to_localised": boot(to_loc, median_of),
        "recovery_frames": boot(list(recov), median_of),
        "recovered_within_budget": wilson_interval(within, kidnapped) if kidnapped else None,
        **suspects_ci,
    }
    return {
        "perturbation": name,
        "severity": float(severity),
        "episodes": n,
        "success_rate": n_succ / n,
        "collision_rate": n_coll / n,
        "p50_loc_error_m": float(np.percentile(err, 50)) if err.size else None,
        "p95_loc_error_m": s["p95_loc_error_m"],
        "time_localised": s["time_localised"],
        "confidently_wrong_rate": s["confidently_wrong_rate"],
        "stuck_wrong_rate": s["stuck_wrong_rate"],
        "median_frames_to_localised": s["median_frames_to_localised"],
        "kidnapped_episodes": kidnapped,
        "recovery_frames": float(np.median(done)) if done else None,
        "recovery_frames_per_episode": list(recov),
        "recovered_within_budget": within / kidnapped if kidnapped else None,
        **suspects,
        "ci95": {k: None if v is None else [v[0], v[1]] for k, v in ci.items()},
    }


def run_matrix(
    make_policy: Callable[[gym.Env], Policy],
    agent: str = "pure-pursuit",
    env_id: str = DEFAULT_ENV,
    perturbations: Sequence[str] = PERTURBATION_NAMES,
    severities: Sequence[float] = DEFAULT_SEVERITIES,
    episodes: int = DEFAULT_EPISODES,
    seed: int = 0,
    task: str | None = "path",
    overrides: dict[str, Any] | None = None,
    progress: Callable[[str], None] | None = None,
    on_episode: Callable[[], None] | None = None,
    scenario: str | None = None,
    num_envs: int = 1,
) -> dict[str, Any]:
    """The whole matrix (baseline row first).

    Parameters
    ----------
    make_policy : callable
        Builds the policy from the first cell's env (called once; the policy then drives
        every cell).
    agent : str
        The policy's name in the result; ``oracle`` gets the true-pose observation, so
        kidnapping measures AMCL alone.
    env_id : str
        ``LRPRadarNavFast-v0`` (default) or ``LRPRadarNav-v0`` (signal-level radar).
    task : {"path", "goal"}
        ``path``: the paper scenario ``ipin2023``; ``goal``: sampled start/goal pairs.
    overrides : dict, optional
        Scenario settings applied to every cell (before the cell's perturbation).
    progress : callable, optional
        Called with a label before each cell.
    on_episode : callable, optional
        Called after every episode.
    scenario : str, optional
        Scenario name or file; ``task`` then sets its ``task.mode`` (None: keep it).
    num_envs : int
        Robots driven at once per cell (the same episodes as one at a time).

    Returns
    -------
    dict
        ``{"agent", "env_id", "task", "episodes", "seed", "cells": [...]}``.
    """
    _check(perturbations, severities, episodes)
    scenario, overrides = scenario_and_task(task, scenario, overrides)
    policy = None
    cells = []
    for name, sev, cell in matrix_cells(perturbations, severities, overrides):
        if progress is not None:
            progress(cell_label(name, sev))
        env = make_eval_env(agent, env_id, scenario, overrides=cell or None)
        try:
            if policy is None:
                policy = make_policy(env)
            cells.append(
                run_cell(env, policy, name, sev, episodes, seed, on_episode, num_envs=num_envs)
            )
        finally:
            env.close()
    head = {"agent": agent, "env_id": env_id, "scenario": scenario, "task": task}
    return {**head, "episodes": episodes, "seed": seed, "cells": cells}


def matrix_cells(
    perturbations: Sequence[str], severities: Sequence[float], overrides: dict[str, Any] | None
) -> list[tuple[str, float, dict[str, Any]]]:
    """The matrix's cells in order, baseline first: (perturbation, severity, the cell's
    overrides: ``overrides`` with its perturbation)."""
    spec = [(BASELINE, 0.0)] + [(p, float(s)) for p in perturbations for s in severities]
    return [(n, s, deep_merge(overrides or {}, cell_overrides(n, s))) for n, s in spec]


def cell_label(name: str, severity: float) -> str:
    """``baseline`` or ``name @ severity`` (progress lines, unit names)."""
    return f"{name} @ {severity:g}" if name != BASELINE else "baseline"


def scenario_and_task(
    task: str | None, scenario: str | None, overrides: dict[str, Any] | None
) -> tuple[str | None, dict[str, Any] | None]:
    """The matrix's scenario (``ipin2023`` for the path task, sampled goals in the default
    room for ``goal``) and the overrides with a given scenario's ``task.mode`` set."""
    if task not in ("path", "goal", None) or (task is None and scenario is None):
        raise ValueError(f"task: must be 'path' or 'goal', got {task!r}")
    if scenario is None:
        return ("ipin2023" if task == "path" else None), overrides
    if task is not None:
        overrides = deep_merge(overrides or {}, {"task": {"mode": task}})
    return scenario, overrides


def plot_matrix(result: dict[str, Any]):
    """Heat maps of the success rate and the share of steps localised (perturbation x severity).

    The baseline (no perturbation) is the first row, in the first column. Each cell shows the
    value and its 95 % interval (``ci95``); the colour is the value.
    """
    import matplotlib.pyplot as plt

    cells = result["cells"]
    names = list(dict.fromkeys(c["perturbation"] for c in cells))
    sevs = sorted({c["severity"] for c in cells if c["perturbation"] != BASELINE}) or [0.0]
    fig, axes = plt.subplots(
        1, 2, figsize=(3.2 + 2.0 * len(sevs), 1.3 + 0.55 * len(names)), squeeze=False
    )
    for ax, key, title in (
        (axes[0, 0], "success_rate", "success"),
        (axes[0, 1], "time_localised", "steps localised (< 0.2 m)"),
    ):
        grid = np.full((len(names), len(sevs)), np.nan)
        text = np.full(grid.shape, "", dtype=object)
        for c in cells:
            i = names.index(c["perturbation"])
            j = 0 if c["perturbation"] == BASELINE else sevs.index(c["severity"])
            v, ci = c[key], (c.get("ci95") or {}).get(key)
            if v is None:
                continue
            grid[i, j] = v
            lo, hi = ("", "") if ci is None else (f"{100 * ci[0]:.0f}", f"{100 * ci[1]:.0f}")
            # One number when both ends round alike (as in the CLI table).
            text[i, j] = f"{100 * v:.0f} %" + (
                "" if ci is None else f"\n{lo}-{hi}" if lo != hi else f"\n{lo}"
            )
        cmap = plt.get_cmap("RdYlGn").with_extremes(bad="0.92")  # grey: no such cell
        im = ax.imshow(np.ma.masked_invalid(grid), cmap=cmap, vmin=0.0, vmax=1.0, aspect="auto")
        for (i, j), t in np.ndenumerate(text):
            if t:
                ax.text(j, i, t, ha="center", va="center", fontsize=7, linespacing=1.1)
        ax.set_xticks(range(len(sevs)), [f"{s:g}" for s in sevs])
        ax.set_yticks(range(len(names)), names)
        ax.set_xlabel("severity (baseline row: none)")
        ax.set_title(f"{title}: value, 95 % interval", fontsize=9)
        fig.colorbar(im, ax=ax, fraction=0.046)
    fig.suptitle(
        f"{result['agent']} on {result.get('scenario') or result['env_id']}, "
        f"{result['episodes']} episodes/cell",
        fontsize=10,
    )
    fig.tight_layout()
    return fig
