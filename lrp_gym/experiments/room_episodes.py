"""Closed-loop episodes on generated rooms: ``lrp-gym evaluate``'s machinery on
``random_scenario`` draws.

:func:`run_rooms` drives an agent through the same episode seeds in each room
``random_scenario(default_rng(room_seed))`` (the user's scenario overrides merged in, as
:mod:`lrp_gym.experiments.rooms` does for the static experiment), so the per-room numbers are
exactly those of evaluating that room's scenario alone. :func:`summary` gives one row per room
and the metrics pooled over every episode of every room; the pooled
``confidently_wrong_rate`` (converged steps more than
:data:`~lrp_gym.localization.metrics.CONFIDENTLY_WRONG_M` off) measures how far the localiser
can be trusted beyond the paper room.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from lrp_gym.config import ScenarioConfig
from lrp_gym.experiments.episodes import (
    EpisodeResult,
    Policy,
    episode_results,
    make_eval_env,
    nav_env,
    summarize,
)
from lrp_gym.experiments.scenarios import generated_room, reflector_kinds
from lrp_gym.localization.metrics import CONFIDENTLY_WRONG_M

#: A room counts as confidently wrong when more than this share of its converged steps is.
WRONG_ROOM_RATE = 0.01


@dataclass(frozen=True)
class RoomEpisodes:
    """One generated room and the episodes driven in it.

    Attributes
    ----------
    seed : int
        Room seed (``random_scenario(default_rng(seed))``).
    size_m : (float, float, float)
        Room size.
    obstacles, reflectors : int
        Box obstacles and reflectors in the room.
    kinds : str
        The reflector kinds used, sorted and joined by ``+``.
    env_id, task, fidelity : str
        The env id, task mode and radar fidelity the episodes ran with (after the overrides).
    episodes : tuple of EpisodeResult
        In episode-seed order.
    """

    seed: int
    size_m: tuple[float, float, float]
    obstacles: int
    reflectors: int
    kinds: str
    env_id: str
    task: str
    fidelity: str
    episodes: tuple[EpisodeResult, ...]


def run_rooms(
    room_seeds: Iterable[int],
    make_policy: Callable[[gym.Env], Policy],
    *,
    episodes: int,
    seed: int = 0,
    agent: str = "pure-pursuit",
    env_id: str | None = None,
    overrides: dict[str, Any] | None = None,
    small: bool = False,
    num_envs: int = 1,
    progress: Callable[[RoomEpisodes], None] | None = None,
) -> list[RoomEpisodes]:
    """Drive ``episodes`` episodes (seeds ``seed, seed + 1, ...``) in each generated room.

    Parameters
    ----------
    room_seeds : iterable of int
        Room seeds (the room, reflectors, waveform and path follow from the seed alone).
    make_policy : callable
        The agent for one room's env (pure pursuit is built from the env it drives in).
    episodes : int
        Episodes per room, at least 1.
    seed : int
        Seed of the first episode in every room.
    agent : str
        Agent name, for the env (the oracle agent gets the true-pose observation).
    env_id : str, optional
        Gymnasium env id (default: :func:`~lrp_gym.experiments.episodes.make_eval_env`'s).
    overrides : dict, optional
        Nested scenario overrides merged into every room (``--set``, fidelity, task mode).
    small : bool
        Draw the small test rooms instead.
    num_envs : int
        Robots driven at once (the same results as one at a time).
    progress : callable, optional
        Called with each room's result as it is done.

    Returns
    -------
    list of RoomEpisodes
        In room-seed order.
    """
    if episodes < 1:
        raise ValueError(f"episodes: must be at least 1, got {episodes}")
    seeds = list(range(seed, seed + episodes))
    out = []
    for room_seed in room_seeds:
        cfg = generated_room(int(room_seed), overrides, small=small)
        room = run_room(cfg, int(room_seed), make_policy, seeds, agent, env_id, num_envs)
        if progress is not None:
            progress(room)
        out.append(room)
    return out


def run_room(
    cfg: ScenarioConfig,
    room_seed: int,
    make_policy: Callable[[gym.Env], Policy],
    seeds: list[int],
    agent: str = "pure-pursuit",
    env_id: str | None = None,
    num_envs: int = 1,
) -> RoomEpisodes:
    """One room of :func:`run_rooms`: the episodes ``seeds`` in the room ``cfg`` (the draw of
    ``room_seed``, overrides merged in)."""
    env = make_eval_env(agent, env_id, scenario=cfg)
    try:
        try:
            policy = make_policy(env)
        except ValueError as err:  # e.g. a model trained for another room's spaces
            raise ValueError(f"{err} (room seed {room_seed})") from None
        results = episode_results(env, policy, seeds, num_envs)
        used = nav_env(env).cfg
    finally:
        env.close()
    layout = cfg.reflectors.layout
    return RoomEpisodes(
        seed=room_seed,
        size_m=(float(cfg.room.size[0]), float(cfg.room.size[1]), float(cfg.room.size[2])),
        obstacles=len(cfg.room.obstacles),
        reflectors=len(layout),
        kinds=reflector_kinds(cfg),
        env_id=env.spec.id if env.spec is not None else (env_id or ""),
        task=used.task.mode,
        fidelity=used.radar.fidelity,
        episodes=tuple(results),
    )


def converged_steps(results: Iterable[EpisodeResult]) -> tuple[int, int]:
    """(converged steps, converged steps more than ``CONFIDENTLY_WRONG_M`` off) of episodes."""
    conv = wrong = 0
    for r in results:
        conv += int(np.sum(r.converged))
        wrong += int(np.sum(r.converged & (r.loc_error_m > CONFIDENTLY_WRONG_M)))
    return conv, wrong


def room_row(room: RoomEpisodes) -> dict[str, Any]:
    """One room's facts and headline metrics (JSON-friendly: None where undefined)."""
    m = summarize(list(room.episodes))
    conv, wrong = converged_steps(room.episodes)
    return {
        "seed": room.seed,
        "size_m": list(room.size_m),
        "obstacles": room.obstacles,
        "reflectors": room.reflectors,
        "kinds": room.kinds,
        "episodes": len(room.episodes),
        **{
            k: m[k]
            for k in (
                "success_rate",
                "collision_rate",
                "time_localised",
                "converged_share",
                "confidently_wrong_rate",
                "stuck_wrong_rate",
            )
        },
        "converged_steps": conv,
        "wrong_converged_steps": wrong,
    }


def summary(rooms: list[RoomEpisodes]) -> dict[str, Any]:
    """Per-room rows and the metrics pooled over all episodes of all rooms.

    Returns
    -------
    dict
        ``rooms``, ``pooled`` (:func:`~lrp_gym.experiments.episodes.summarize` on every
        episode, its ``reliability`` bins included), ``converged_steps`` and
        ``wrong_converged_steps`` (all rooms), ``rooms_confidently_wrong_over_1pct``
        (rooms whose ``confidently_wrong_rate`` exceeds :data:`WRONG_ROOM_RATE`; a room with no
        converged step is not wrong) and ``per_room`` (:func:`room_row`). JSON-friendly.
    """
    if not rooms:
        raise ValueError("rooms: at least one room is needed")
    rows = [room_row(r) for r in rooms]
    pooled = summarize([e for r in rooms for e in r.episodes])
    wrong_rooms = sum(
        r["confidently_wrong_rate"] is not None and r["confidently_wrong_rate"] > WRONG_ROOM_RATE
        for r in rows
    )
    conv, wrong = converged_steps(e for r in rooms for e in r.episodes)
    return {
        "rooms": len(rooms),
        "pooled": pooled,
        "converged_steps": conv,
        "wrong_converged_steps": wrong,
        "rooms_confidently_wrong_over_1pct": int(wrong_rooms),
        "per_room": rows,
    }
