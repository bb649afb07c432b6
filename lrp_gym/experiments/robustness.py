"""Robustness matrix: perturbation x severity, closed-loop episodes on fixed seeds per cell.

Every cell runs ``episodes`` episodes on seeds ``seed .. seed + episodes - 1`` with the
runner of :mod:`lrp_gym.experiments.episodes` (same policy, same env id, same scenario; only the
``perturbations`` override differs), plus one baseline row without perturbation. Per cell:
success rate, collision rate, localisation error percentiles (p50, p95, pooled over all steps),
the share of steps localised (error < :data:`LOCALISED_M`) and, for ``kidnapping``, the frames
AMCL needs to get back within :data:`LOCALISED_M` of the truth after the jump.

Default setting: the fast (detections-level) env ``LRPRadarNavFast-v0`` on the paper scenario
in path mode (``ipin2023``: its 15-waypoint path, the same start every episode; seeds change
sensor noise and the perturbations' draws). ``task="goal"`` uses sampled start/goal pairs.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from lrp_gym.config import PerturbationsConfig, deep_merge
from lrp_gym.experiments.episodes import Policy, make_eval_env, nav_env, run_episode, summarize
from lrp_gym.perturbations.robot_motion import Kidnapping

LOCALISED_M = 0.2
RECOVERY_BUDGET_FRAMES = 15
DEFAULT_ENV = "LRPRadarNavFast-v0"
DEFAULT_SEVERITIES = (0.25, 0.5, 1.0)
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
) -> dict[str, Any]:
    """Run one cell's episodes in ``env`` (already built with the cell's overrides)."""
    results, recov, kidnapped = [], [], 0
    for i in range(episodes):
        res = run_episode(env, policy, seed + i)
        results.append(res)
        pert = nav_env(env).perturbations
        kid = pert.get("kidnapping") if pert is not None else None
        if isinstance(kid, Kidnapping) and kid.kidnap_frame is not None:
            kidnapped += 1
            recov.append(recovery_frames(res.loc_error_m, kid.kidnap_frame))
        if on_episode is not None:
            on_episode()
    s = summarize(results)
    err = np.concatenate([r.loc_error_m for r in results])
    done = [r for r in recov if r is not None]
    return {
        "perturbation": name,
        "severity": float(severity),
        "episodes": episodes,
        "success_rate": s["success_rate"],
        "collision_rate": s["collision_rate"],
        "p50_loc_error_m": float(np.percentile(err, 50)) if err.size else None,
        "p95_loc_error_m": s["p95_loc_error_m"],
        "time_localised": s["time_localised"],
        "kidnapped_episodes": kidnapped,
        "recovery_frames": float(np.median(done)) if done else None,
        "recovery_frames_per_episode": recov,
        "recovered_within_budget": (
            sum(r is not None and r <= RECOVERY_BUDGET_FRAMES for r in recov) / kidnapped
            if kidnapped
            else None
        ),
    }


def run_matrix(
    make_policy: Callable[[gym.Env], Policy],
    agent: str = "pure-pursuit",
    env_id: str = DEFAULT_ENV,
    perturbations: Sequence[str] = PERTURBATION_NAMES,
    severities: Sequence[float] = DEFAULT_SEVERITIES,
    episodes: int = 10,
    seed: int = 0,
    task: str | None = "path",
    overrides: dict[str, Any] | None = None,
    progress: Callable[[str], None] | None = None,
    on_episode: Callable[[], None] | None = None,
    scenario: str | None = None,
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

    Returns
    -------
    dict
        ``{"agent", "env_id", "task", "episodes", "seed", "cells": [...]}``.
    """
    _check(perturbations, severities, episodes)
    if task not in ("path", "goal", None) or (task is None and scenario is None):
        raise ValueError(f"task: must be 'path' or 'goal', got {task!r}")
    if scenario is None:
        scenario = "ipin2023" if task == "path" else None
    elif task is not None:
        overrides = deep_merge(overrides or {}, {"task": {"mode": task}})
    cells_spec = [(BASELINE, 0.0)] + [(p, s) for p in perturbations for s in severities]
    policy = None
    cells = []
    for name, sev in cells_spec:
        if progress is not None:
            progress(f"{name} @ {sev:g}" if name != BASELINE else "baseline")
        cell = deep_merge(overrides or {}, cell_overrides(name, sev))
        env = make_eval_env(agent, env_id, scenario, overrides=cell or None)
        try:
            if policy is None:
                policy = make_policy(env)
            cells.append(run_cell(env, policy, name, sev, episodes, seed, on_episode))
        finally:
            env.close()
    return {
        "agent": agent,
        "env_id": env_id,
        "scenario": scenario,
        "task": task,
        "episodes": episodes,
        "seed": seed,
        "cells": cells,
    }


def plot_matrix(result: dict[str, Any]):
    """Heatmaps of success rate and p95 localisation error (perturbation x severity)."""
    import matplotlib.pyplot as plt

    cells = [c for c in result["cells"] if c["perturbation"] != BASELINE]
    base = next((c for c in result["cells"] if c["perturbation"] == BASELINE), None)
    names = list(dict.fromkeys(c["perturbation"] for c in cells))
    sevs = sorted({c["severity"] for c in cells})
    fig, axes = plt.subplots(
        1, 2, figsize=(4 + 1.6 * len(sevs), 1.2 + 0.5 * len(names)), squeeze=False
    )
    for ax, key, title, cmap in (
        (axes[0, 0], "success_rate", "success rate", "RdYlGn"),
        (axes[0, 1], "p95_loc_error_m", "p95 localisation error (m)", "viridis_r"),
    ):
        grid = np.full((len(names), len(sevs)), np.nan)
        for c in cells:
            v = c[key]
            grid[names.index(c["perturbation"]), sevs.index(c["severity"])] = (
                np.nan if v is None else v
            )
        vmax = (
            1.0
            if key == "success_rate"
            else max(np.nanmax(grid) if np.isfinite(grid).any() else 1.0, 0.2)
        )
        im = ax.imshow(grid, cmap=cmap, vmin=0.0, vmax=vmax, aspect="auto")
        for (i, j), v in np.ndenumerate(grid):
            ax.text(j, i, "-" if np.isnan(v) else f"{v:.2f}", ha="center", va="center", fontsize=8)
        ax.set_xticks(range(len(sevs)), [f"{s:g}" for s in sevs])
        ax.set_yticks(range(len(names)), names)
        ax.set_xlabel("severity")
        bt = "" if base is None or base[key] is None else f" (baseline {base[key]:.2f})"
        ax.set_title(title + bt, fontsize=9)
        fig.colorbar(im, ax=ax, fraction=0.046)
    fig.suptitle(
        f"{result['agent']} on {result['env_id']}, {result['episodes']} episodes/cell", fontsize=10
    )
    fig.tight_layout()
    return fig
