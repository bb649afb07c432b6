"""Closed-loop episodes of any policy in the env, on fixed seeds, and their metrics.

Episodes run on seeds ``seed, seed + 1, ...`` so two policies meet the same start poses, goals
and sensor noise draws. Per episode it records success, collision, time to goal, driven path
length, the localisation error at every step (``info["position_error_m"]``) and the
cross-track error (distance of the *true* position to the waypoint polyline). Policies come
from outside (``agents``) through the :class:`Policy` protocol, so the library never imports
them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import gymnasium as gym
import numpy as np

import lrp_gym.envs  # noqa: F401  (registers the env ids)
from lrp_gym.config import ScenarioConfig
from lrp_gym.envs.nav_env import LRPRadarNavEnv
from lrp_gym.localization.metrics import trust_metrics
from lrp_gym.perturbations import PerturbationSet
from lrp_gym.perturbations.layout import DisplacedReflector
from lrp_gym.perturbations.robot_motion import Kidnapping
from lrp_gym.perturbations.sensing import Shadowing

DEFAULT_ENV = "LRPRadarNav-v0"
ORACLE_ENV = "LRPRadarNavOracle-v0"


class Policy(Protocol):
    """What the episode runner drives: one action per observation, reset between episodes."""

    def reset(self) -> None:
        """Forget any per-episode state (called before every episode)."""

    def act(self, observation: Any) -> np.ndarray:
        """The action for one observation (deterministic)."""
        ...


def nav_env(env: gym.Env) -> LRPRadarNavEnv:
    """The LRP env inside ``env``'s wrappers (ValueError naming ``env`` for any other env)."""
    base = env.unwrapped
    if not isinstance(base, LRPRadarNavEnv):
        raise ValueError(f"env: expected an LRPRadarNav env, got {type(base).__name__}")
    return base


def _frame(env: gym.Env) -> np.ndarray:
    """The env's rendered RGB frame (created with ``render_mode="rgb_array"``)."""
    return np.asarray(env.render())


def make_eval_env(
    agent: str,
    env_id: str | None = None,
    scenario: str | ScenarioConfig | None = None,
    render_mode: str | None = None,
    **env_kwargs: Any,
) -> gym.Env:
    """The env an agent is evaluated in (the oracle agent gets the true-pose observation)."""
    if env_id is None:
        env_id = ORACLE_ENV if agent == "oracle" else DEFAULT_ENV
    elif agent == "oracle":
        env_kwargs.setdefault("observation", "oracle")
    if env_id.split(":")[-1] not in gym.registry:
        known = ", ".join(k for k in gym.registry if k.startswith("LRP"))
        raise ValueError(f"env_id: unknown env id {env_id!r}; known: {known}")
    if scenario is not None:
        env_kwargs["scenario"] = scenario
    return gym.make(env_id, render_mode=render_mode, **env_kwargs)


def cross_track_m(points_xy: np.ndarray, waypoints_m: np.ndarray) -> np.ndarray:
    """Distance of each point (N, 2) to the polyline through ``waypoints_m`` (K, 2)."""
    p = np.asarray(points_xy, dtype=float)[:, None, :]
    a, b = waypoints_m[:-1][None], waypoints_m[1:][None]
    ab = b - a
    len2 = np.maximum(np.sum(ab**2, axis=-1), 1e-12)
    t = np.clip(np.sum((p - a) * ab, axis=-1) / len2, 0.0, 1.0)
    d = np.linalg.norm(p - (a + t[..., None] * ab), axis=-1)
    return d.min(axis=1)


@dataclass
class EpisodeResult:
    """What one episode measured (arrays are per step, after each action)."""

    seed: int
    success: bool
    collision: bool
    steps: int
    episode_return: float
    path_length_m: float
    time_to_goal_s: float | None
    loc_error_m: np.ndarray = field(repr=False)
    converged: np.ndarray = field(repr=False)
    cross_track_m: np.ndarray = field(repr=False)
    true_xy: np.ndarray = field(repr=False)
    est_xy: np.ndarray = field(repr=False)
    waypoints_m: np.ndarray = field(repr=False)
    confidence: np.ndarray | None = field(default=None, repr=False)
    kidnap_frame: int | None = None  # the frame a kidnapping perturbation moved the robot
    #: Reflectors a perturbation moved or hid, the last frame before each was (0: moved
    #: before the episode; empty: all 0), and the first frame each reflector was named in
    #: ``info["suspect_reflectors"]``.
    perturbed_reflectors: tuple[int, ...] = ()
    perturbed_after_frame: tuple[int, ...] = ()
    suspect_first_frame: dict[int, int] = field(default_factory=dict, repr=False)

    def row(self) -> dict[str, Any]:
        """Scalar summary of the episode (JSON-friendly)."""
        return {
            "seed": self.seed,
            "success": self.success,
            "collision": self.collision,
            "steps": self.steps,
            "return": self.episode_return,
            "time_to_goal_s": self.time_to_goal_s,
            "path_length_m": self.path_length_m,
            "mean_loc_error_m": float(np.mean(self.loc_error_m)) if self.steps else None,
            "max_loc_error_m": float(np.max(self.loc_error_m)) if self.steps else None,
            "mean_cross_track_m": float(np.mean(self.cross_track_m)) if self.steps else None,
        }


class EpisodeRecorder:
    """Collects one episode's per-step infos into an :class:`EpisodeResult`.

    Parameters
    ----------
    seed : int
        The episode's seed.
    info : dict
        The info of ``reset`` (the start pose).
    waypoints_m : ndarray (K, 2)
        The episode's path.
    dt_s : float
        Frame period (time to goal).
    """

    def __init__(self, seed: int, info: dict[str, Any], waypoints_m: np.ndarray, dt_s: float):
        self.seed, self.waypoints_m, self.dt_s = seed, np.asarray(waypoints_m, float), dt_s
        self.true_xy = [np.asarray(info["true_pose"][:2], dtype=float)]
        self.est_xy = [np.asarray(info["est_pose"][:2], dtype=float)]
        self.errors: list[float] = []
        self.converged: list[bool] = []
        self.confidence: list[float] = []
        self.episode_return, self.collision, self.success, self.steps = 0.0, False, False, 0
        self.suspect_first_frame: dict[int, int] = {}

    def add(self, reward: float, info: dict[str, Any]) -> None:
        """One step's reward and info."""
        self.steps += 1
        self.episode_return += float(reward)
        self.true_xy.append(np.asarray(info["true_pose"][:2], dtype=float))
        self.est_xy.append(np.asarray(info["est_pose"][:2], dtype=float))
        self.errors.append(info["position_error_m"])
        self.converged.append(info["converged"])
        self.confidence.append(info.get("localization_confidence", float(info["converged"])))
        self.collision |= bool(info["collision"])
        self.success |= bool(info["is_success"])
        for j in info.get("suspect_reflectors", ()):
            self.suspect_first_frame.setdefault(int(j), self.steps)

    def result(self, perturbations: PerturbationSet | None = None) -> EpisodeResult:
        """The episode's result; ``perturbations``, the episode's, tell the frame of a
        kidnapping and which reflectors were moved or hidden."""
        txy = np.asarray(self.true_xy)
        return EpisodeResult(
            seed=self.seed,
            success=self.success,
            collision=self.collision,
            steps=self.steps,
            episode_return=self.episode_return,
            path_length_m=float(np.sum(np.linalg.norm(np.diff(txy, axis=0), axis=1))),
            time_to_goal_s=self.steps * self.dt_s if self.success else None,
            loc_error_m=np.asarray(self.errors, dtype=float),
            converged=np.asarray(self.converged, dtype=bool),
            confidence=np.asarray(self.confidence, dtype=float),
            cross_track_m=cross_track_m(txy[1:], self.waypoints_m),
            true_xy=txy,
            est_xy=np.asarray(self.est_xy),
            waypoints_m=self.waypoints_m,
            kidnap_frame=kidnap_frame(perturbations),
            perturbed_reflectors=perturbed_reflectors(perturbations),
            perturbed_after_frame=perturbed_after_frame(perturbations),
            suspect_first_frame=dict(self.suspect_first_frame),
        )


def run_episode(
    env: gym.Env, policy: Policy, seed: int, frames: list[np.ndarray] | None = None
) -> EpisodeResult:
    """Run one episode from ``env.reset(seed=seed)``; append rendered frames to ``frames``."""
    obs, info = env.reset(seed=seed)
    base = nav_env(env)
    if base.path is None:  # reset() always sets the path
        raise RuntimeError("the env has no path after reset")
    record = EpisodeRecorder(seed, info, base.path.waypoints_m, float(base.cfg.task.frame_period_s))
    if frames is not None:
        frames.append(_frame(env))
    policy.reset()
    done = False
    while not done:
        obs, reward, terminated, truncated, info = env.step(policy.act(obs))
        done = terminated or truncated
        record.add(float(reward), info)
        if frames is not None:
            frames.append(_frame(env))
    return record.result(base.perturbations)


def summarize(results: list[EpisodeResult]) -> dict[str, Any]:
    """Aggregate metrics over episodes (errors pooled over all steps of all episodes)."""
    err = np.concatenate([r.loc_error_m for r in results])
    conv = np.concatenate([r.converged for r in results])
    xt = np.concatenate([r.cross_track_m for r in results])
    ttg = [r.time_to_goal_s for r in results if r.time_to_goal_s is not None]

    def stat(fn, a):
        return float(fn(a)) if a.size else None

    return {
        "episodes": len(results),
        "success_rate": float(np.mean([r.success for r in results])),
        "collision_rate": float(np.mean([r.collision for r in results])),
        "mean_return": float(np.mean([r.episode_return for r in results])),
        "mean_steps": float(np.mean([r.steps for r in results])),
        "mean_time_to_goal_s": float(np.mean(ttg)) if ttg else None,
        "mean_path_length_m": float(np.mean([r.path_length_m for r in results])),
        "mean_loc_error_m": stat(np.mean, err),
        "p95_loc_error_m": stat(lambda a: np.percentile(a, 95), err),
        "max_loc_error_m": stat(np.max, err),
        "mean_loc_error_converged_m": stat(np.mean, err[conv]),
        "mean_cross_track_m": stat(np.mean, xt),
        "max_cross_track_m": stat(np.max, xt),
        **trust_metrics(
            [r.loc_error_m for r in results],
            [r.converged for r in results],
            [r.converged if r.confidence is None else r.confidence for r in results],
        ),
    }


def run_episodes(
    policy: Policy,
    env: gym.Env,
    n_episodes: int,
    seed: int = 0,
    gif_path: str | Path | None = None,
    progress: Callable[[EpisodeResult], None] | None = None,
    num_envs: int = 1,
) -> dict[str, Any]:
    """Run ``n_episodes`` on seeds ``seed, seed + 1, ...`` and summarise them.

    Parameters
    ----------
    policy : Policy
        Any object with ``reset()`` and ``act(observation) -> action``.
    env : gymnasium.Env
        Created with ``render_mode="rgb_array"`` when ``gif_path`` is given.
    n_episodes : int
        At least 1.
    seed : int
        Seed of the first episode.
    gif_path : path, optional
        Write the first episode as an animated GIF.
    progress : callable, optional
        Called with each :class:`EpisodeResult` as it finishes.
    num_envs : int
        Robots driven at once in one batch (:mod:`lrp_gym.experiments.batched_episodes`,
        ``env``'s scenario); the results are those of the sequential run, seed by seed. The
        GIF episode runs alone first.

    Returns
    -------
    dict
        :func:`summarize`'s metrics plus ``"per_episode"`` rows and ``"seed"``.
    """
    if n_episodes < 1:
        raise ValueError(f"n_episodes: must be at least 1, got {n_episodes}")
    results = []
    seeds = list(range(seed, seed + n_episodes))
    if gif_path is not None:
        frames: list[np.ndarray] = []
        results.append(run_episode(env, policy, seeds.pop(0), frames))
        write_gif(frames, gif_path, fps=env.metadata.get("render_fps", 4))
        if progress is not None:
            progress(results[-1])
    results += episode_results(env, policy, seeds, num_envs, progress)
    summary = summarize(results)
    summary["seed"] = seed
    summary["per_episode"] = [r.row() for r in results]
    summary["_results"] = results  # for plotting; dropped before JSON output
    return summary


def episode_results(
    env: gym.Env,
    policy: Policy,
    seeds: list[int],
    num_envs: int = 1,
    progress: Callable[[EpisodeResult], None] | None = None,
) -> list[EpisodeResult]:
    """One episode per seed, in ``env`` or, with ``num_envs`` > 1, in a batch of robots with
    ``env``'s scenario (the same results); in seed order."""
    if num_envs < 1:
        raise ValueError(f"num_envs: must be at least 1, got {num_envs}")
    if num_envs > 1 and len(seeds) > 1:
        from lrp_gym.experiments.batched_episodes import run_batched

        return run_batched(policy, nav_env(env).cfg, seeds, num_envs, progress)
    results = []
    for s in seeds:
        results.append(run_episode(env, policy, s))
        if progress is not None:
            progress(results[-1])
    return results


def kidnap_frame(perturbations: PerturbationSet | None) -> int | None:
    """The frame of this episode's kidnapping, if one happened."""
    kid = perturbations.get("kidnapping") if perturbations is not None else None
    return kid.kidnap_frame if isinstance(kid, Kidnapping) else None


def perturbed_reflectors(perturbations: PerturbationSet | None) -> tuple[int, ...]:
    """Reflectors this episode's perturbations moved (displaced reflector) or hid
    (shadowing): the ones the reflector monitor may rightly name."""
    if perturbations is None:
        return ()
    out: set[int] = set()
    moved = perturbations.get("displaced_reflector")
    if isinstance(moved, DisplacedReflector):
        out |= {int(j) for j in moved.moved}
    hidden = perturbations.get("shadowing")
    if isinstance(hidden, Shadowing):
        out |= {int(j) for j in hidden.targets}
    return tuple(sorted(out))


def perturbed_after_frame(perturbations: PerturbationSet | None) -> tuple[int, ...]:
    """For each of :func:`perturbed_reflectors`, the last frame before the perturbation
    touched it: 0 for a moved reflector (moved before the episode), the frame before the
    shadowing began for a hidden one. A reflector both moved and hidden counts from 0."""
    reflectors = perturbed_reflectors(perturbations)
    if not reflectors:
        return ()
    hidden = perturbations.get("shadowing")
    moved = perturbations.get("displaced_reflector")
    moved_set = {int(j) for j in moved.moved} if isinstance(moved, DisplacedReflector) else set()
    start = hidden.start if isinstance(hidden, Shadowing) else 1
    return tuple(0 if j in moved_set else max(0, start - 1) for j in reflectors)


def write_gif(frames: list[np.ndarray], path: str | Path, fps: float = 4.0) -> Path:
    """Write RGB frames (H, W, 3) as an animated GIF (atomic rename)."""
    import imageio.v2 as imageio

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.stem + ".tmp" + path.suffix)
    imageio.mimsave(
        tmp, [np.asarray(f, dtype=np.uint8) for f in frames], duration=1.0 / fps, loop=0
    )
    tmp.replace(path)
    return path


def public(summary: dict[str, Any]) -> dict[str, Any]:
    """The summary without private (non-JSON) entries."""
    return {k: v for k, v in summary.items() if not k.startswith("_")}
