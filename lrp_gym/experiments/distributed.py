"""The units of work of the studies that run on Ray (:mod:`lrp_gym.experiments.cluster`).

- Episodes: a slice of one cell's seeds (:class:`EpisodeSlice`). Every episode seeds itself
  from its own seed, so the slices of a cell, put back in seed order, are the episodes the
  one-process run drives; the cell's statistics (bootstrap seeded with the study's seed) are
  then computed once, on the driver, from all of them.
- Layout candidates: a slice of the random layouts, drawn up front from the search's one
  generator (:func:`score_layouts`).

Results travel to the sidecar as JSON (:func:`episode_to_json`, :func:`episode_from_json`,
exact: floats are written with ``repr``), so a resumed study gives the same numbers.
"""

from __future__ import annotations

import json
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from lrp_gym.experiments.episodes import EpisodeResult, Policy, episode_results, make_eval_env

#: Episodes per Ray task: small enough to keep two workers busy on one 100-episode cell,
#: large enough that a task (a few seconds) outweighs its scheduling. Fixed, so the units of
#: a study, and the keys of its sidecar, do not depend on the cluster's size.
EPISODES_PER_TASK = 5
#: Candidate layouts per Ray task.
CANDIDATES_PER_TASK = 50
_ARRAYS = {
    "loc_error_m": float,
    "converged": bool,
    "cross_track_m": float,
    "true_xy": float,
    "est_xy": float,
    "waypoints_m": float,
    "confidence": float,
}


@dataclass(frozen=True)
class EpisodeSlice:
    """Some episodes of one cell: the env to build and the seeds to run in it.

    Attributes
    ----------
    agent, env_id, scenario : str or None
        As :func:`lrp_gym.experiments.episodes.make_eval_env` takes them.
    overrides : dict or None
        The cell's scenario overrides (its perturbation included).
    seeds : tuple of int
    make_policy : callable
        Builds the policy from the env (picklable: Ray sends it to the workers).
    num_envs : int
        Robots driven at once inside the task (the same episodes).
    """

    agent: str
    env_id: str | None
    scenario: Any  # a scenario name, or a ScenarioConfig (see unit_scenario)
    overrides: dict[str, Any] | None
    seeds: tuple[int, ...]
    make_policy: Callable[[gym.Env], Policy]
    num_envs: int = 1


#: A worker keeps the last few envs (and their policies): the slices of one cell reuse them.
_ENVS: OrderedDict[str, tuple[gym.Env, Policy]] = OrderedDict()
_MAX_ENVS = 4


def unit_scenario(scenario: Any) -> Any:
    """What a task gets as its scenario: a name as is, a YAML file loaded here (a worker's
    folder, or node, need not have the file)."""
    if isinstance(scenario, str) and Path(scenario).is_file():
        from lrp_gym.config import load_scenario

        return load_scenario(scenario)
    return scenario


def _key(value: Any) -> Any:
    return value.to_dict() if hasattr(value, "to_dict") else str(value)


def _env_and_policy(s: EpisodeSlice) -> tuple[gym.Env, Policy]:
    key = json.dumps([s.agent, s.env_id, s.scenario, s.overrides], sort_keys=True, default=_key)
    if key not in _ENVS:
        env = make_eval_env(s.agent, s.env_id, s.scenario, overrides=s.overrides or None)
        _ENVS[key] = (env, s.make_policy(env))
        while len(_ENVS) > _MAX_ENVS:
            _ENVS.popitem(last=False)[1][0].close()
    _ENVS.move_to_end(key)
    return _ENVS[key]


def run_slice(s: EpisodeSlice) -> list[EpisodeResult]:
    """The slice's episodes, in seed order (a Ray task)."""
    env, policy = _env_and_policy(s)
    return episode_results(env, policy, list(s.seeds), s.num_envs)


def seed_slices(seed: int, episodes: int, size: int = EPISODES_PER_TASK) -> list[tuple[int, ...]]:
    """Seeds ``seed .. seed + episodes - 1`` cut into consecutive slices of ``size``."""
    seeds = list(range(seed, seed + episodes))
    return [tuple(seeds[i : i + size]) for i in range(0, episodes, size)]


def slice_key(label: str, seeds: Sequence[int]) -> str:
    """A unit's name in the sidecar, e.g. ``clutter@0.5/seeds 10-14``."""
    return f"{label}/seeds {seeds[0]}-{seeds[-1]}"


def episode_to_json(r: EpisodeResult) -> dict[str, Any]:
    """One episode's result as JSON values (arrays as nested lists, exact floats)."""
    out: dict[str, Any] = {}
    for f in fields(r):
        v = getattr(r, f.name)
        if isinstance(v, np.ndarray):
            v = v.tolist()
        elif f.name == "suspect_first_frame":
            v = [[int(k), int(n)] for k, n in v.items()]
        elif f.name in ("perturbed_reflectors", "perturbed_after_frame"):
            v = [int(j) for j in v]
        out[f.name] = v
    return out


def episode_from_json(d: dict[str, Any]) -> EpisodeResult:
    """The inverse of :func:`episode_to_json`."""
    kw = dict(d)
    for name, dtype in _ARRAYS.items():
        if kw.get(name) is not None:
            kw[name] = np.asarray(kw[name], dtype=dtype)
    kw["suspect_first_frame"] = {int(k): int(n) for k, n in kw["suspect_first_frame"]}
    kw["perturbed_reflectors"] = tuple(kw["perturbed_reflectors"])
    kw["perturbed_after_frame"] = tuple(kw.get("perturbed_after_frame", ()))
    return EpisodeResult(**kw)


def encode_episodes(results: list[EpisodeResult]) -> list[dict[str, Any]]:
    """A slice's results for the sidecar."""
    return [episode_to_json(r) for r in results]


def decode_episodes(rows: list[dict[str, Any]]) -> list[EpisodeResult]:
    """A slice's results read back from the sidecar."""
    return [episode_from_json(r) for r in rows]


@dataclass(frozen=True)
class LayoutSlice:
    """Some candidate layouts (k, M, 2) of one search, and the problem that scores them."""

    problem: Any  # lrp_gym.placement.search.PlacementProblem
    layouts_xy_m: np.ndarray


def score_slice(s: LayoutSlice) -> list[float]:
    """The coarse ambiguous fraction of each layout of the slice (a Ray task)."""
    return [float(s.problem.score(xy)) for xy in s.layouts_xy_m]


def layout_slices(
    problem: Any, layouts_xy_m: np.ndarray, size: int = CANDIDATES_PER_TASK
) -> list[tuple[str, LayoutSlice]]:
    """The candidates cut into keyed slices of ``size`` (keys name the candidate indices)."""
    n = len(layouts_xy_m)
    return [
        (f"candidates {i}-{min(i + size, n) - 1}", LayoutSlice(problem, layouts_xy_m[i : i + size]))
        for i in range(0, n, size)
    ]


def run_matrix_units(
    make_policy: Callable[[gym.Env], Policy],
    agent: str,
    env_id: str | None,
    perturbations: Sequence[str],
    severities: Sequence[float],
    episodes: int,
    seed: int,
    task: str | None,
    overrides: dict[str, Any] | None = None,
    scenario: str | None = None,
    num_envs: int = 1,
    **run: Any,
) -> dict[str, Any]:
    """:func:`lrp_gym.experiments.robustness.run_matrix` with every cell's episodes cut into
    :class:`EpisodeSlice` units and run by :func:`lrp_gym.experiments.cluster.run_units`
    (``run``: its ``address``, ``sidecar``, ``resume`` and ``on_result``). The same dict, to the
    byte: each cell's statistics are computed here from its episodes in seed order.
    """
    from lrp_gym.experiments import robustness as rb
    from lrp_gym.experiments.cluster import run_units

    rb._check(perturbations, severities, episodes)
    scenario, overrides = rb.scenario_and_task(task, scenario, overrides)
    cells = rb.matrix_cells(perturbations, severities, overrides)
    where = unit_scenario(scenario)
    units = [
        (
            slice_key(rb.cell_label(name, sev), seeds),
            EpisodeSlice(agent, env_id, where, cell or None, seeds, make_policy, num_envs),
        )
        for name, sev, cell in cells
        for seeds in seed_slices(seed, episodes)
    ]
    done = run_units(run_slice, units, encode=encode_episodes, decode=decode_episodes, **run)
    per_cell = len(seed_slices(seed, episodes))
    out = []
    for i, (name, sev, _) in enumerate(cells):
        results = [r for part in done[i * per_cell : (i + 1) * per_cell] for r in part]
        out.append(rb.cell_from_results(name, sev, results, seed))
    head = {"agent": agent, "env_id": env_id, "scenario": scenario, "task": task}
    return {**head, "episodes": episodes, "seed": seed, "cells": out}


def run_episodes_units(
    make_policy: Callable[[gym.Env], Policy],
    agent: str,
    env_id: str | None,
    scenario: str | None,
    overrides: dict[str, Any] | None,
    episodes: int,
    seed: int,
    num_envs: int = 1,
    **run: Any,
) -> dict[str, Any]:
    """:func:`lrp_gym.experiments.episodes.run_episodes` (without the GIF) with the seeds cut
    into :class:`EpisodeSlice` units run by :func:`lrp_gym.experiments.cluster.run_units`
    (``run``: its ``address``, ``sidecar``, ``resume`` and ``on_result``); the same summary."""
    from lrp_gym.experiments.cluster import run_units
    from lrp_gym.experiments.episodes import summarize

    if episodes < 1:
        raise ValueError(f"n_episodes: must be at least 1, got {episodes}")
    where = unit_scenario(scenario)
    units = [
        (
            slice_key("episodes", seeds),
            EpisodeSlice(agent, env_id, where, overrides or None, seeds, make_policy, num_envs),
        )
        for seeds in seed_slices(seed, episodes)
    ]
    parts = run_units(run_slice, units, encode=encode_episodes, decode=decode_episodes, **run)
    results = [r for part in parts for r in part]
    summary = summarize(results)
    summary["seed"] = seed
    summary["per_episode"] = [r.row() for r in results]
    summary["_results"] = results
    return summary
