"""One evaluator for every agent: pure pursuit, PPO (with its VecNormalize statistics), random,
and pure pursuit on the true pose (oracle).

Episodes run on fixed seeds ``seed, seed + 1, ...`` so two agents meet the same start poses,
goals and sensor noise draws. Per episode it records success, collision, time to goal, driven
path length, the localisation error at every step (``info["position_error_m"]``) and the
cross-track error (distance of the *true* position to the waypoint polyline).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import gymnasium as gym
import numpy as np

from lrp_gym.errors import InputError
from lrp_gym.localization.metrics import LOCALISED_M, trust_metrics

AGENTS = ("pure-pursuit", "ppo", "random", "oracle")
MODELS_DIR = Path(__file__).resolve().parent / "models"
DEFAULT_MODEL = MODELS_DIR / "ppo_lrp_nav.zip"
DEFAULT_ENV = "LRPRadarNav-v0"
ORACLE_ENV = "LRPRadarNavOracle-v0"


class Policy(Protocol):
    """Anything with the Stable-Baselines3 ``predict`` signature."""

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]: ...


class RandomPolicy:
    """Uniform random actions from a seeded generator (a lower bound)."""

    def __init__(self, action_space: gym.spaces.Box, rng: np.random.Generator) -> None:
        self.low, self.high = action_space.low, action_space.high
        self.rng = rng

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        shape = np.shape(observation)[:-1] + self.low.shape
        return self.rng.uniform(self.low, self.high, size=shape).astype(np.float32), state


class SB3Policy:
    """A Stable-Baselines3 model plus the observation statistics it was trained with.

    Parameters
    ----------
    model : stable_baselines3.common.base_class.BaseAlgorithm
    obs_normalizer : VecNormalize, optional
        Used only for :meth:`normalize_obs` (frozen: ``training = False``).
    """

    def __init__(self, model: Any, obs_normalizer: Any = None) -> None:
        self.model = model
        self.obs_normalizer = obs_normalizer
        self.observation_space = model.observation_space

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.asarray(observation, dtype=np.float32)
        if self.obs_normalizer is not None:
            obs = self.obs_normalizer.normalize_obs(obs).astype(np.float32)
        return self.model.predict(obs, state, episode_start, deterministic)


def load_ppo(
    model_path: str | Path | None = None, spaces: tuple[Any, Any] = (None, None)
) -> SB3Policy:
    """Load a PPO model zip and its normalisation statistics, without unpickling anything.

    Parameters
    ----------
    model_path : path, optional
        Default: the shipped model.
    spaces : (observation_space, action_space), optional
        The env's spaces; a model trained for other spaces is refused.

    Raises
    ------
    InputError
        The file is missing, is not a readable PPO model, was trained for other spaces, or its
        statistics (``vecnormalize.json`` beside it, see :mod:`agents.model_io`) are missing.
    """
    from agents import model_io

    path = Path(model_path) if model_path is not None else DEFAULT_MODEL
    if not path.is_file():
        hint = (
            " (no model has been shipped yet; train one with `lrp-gym train`)"
            if model_path is None
            else ""
        )
        raise InputError(f"--model: no such model file: {path}{hint}")
    model_io.read_zip_data(path)  # a clear message for a non-model before the statistics
    stats = model_io.find_stats(path)
    if stats is None:
        pkl = model_io.find_stats(path, ".pkl")
        raise InputError(
            f"--model: {path} has no normalisation statistics ({model_io.stats_path_for(path).name} "
            "beside it)"
            + (
                f"; {pkl.name} is a pickle, which runs code when loaded: convert one you trust "
                f"with `python -m agents.model_io {pkl}`"
                if pkl is not None
                else ""
            )
        )
    doc = model_io.read_stats(stats)
    model = model_io.load_ppo_safely(path, spaces)
    return SB3Policy(model, model_io.obs_normalizer(doc))


def make_agent(
    agent: str, env: gym.Env, model_path: str | Path | None = None, seed: int = 0
) -> Policy:
    """The policy for an agent name (see :data:`AGENTS`) acting in ``env``."""
    from agents.pure_pursuit import PurePursuitPolicy

    if agent in ("pure-pursuit", "oracle"):
        return PurePursuitPolicy.from_env(env)
    if agent == "random":
        return RandomPolicy(env.action_space, np.random.default_rng(seed))
    if agent == "ppo":
        return load_ppo(model_path, (env.observation_space, env.action_space))
    raise InputError(f"--agent: unknown agent {agent!r}; choose one of {', '.join(AGENTS)}")


def make_eval_env(
    agent: str,
    env_id: str | None = None,
    scenario: str | None = None,
    render_mode: str | None = None,
    **env_kwargs: Any,
) -> gym.Env:
    """The env an agent is evaluated in (the oracle agent gets the true-pose observation)."""
    import lrp_gym  # noqa: F401  (registers the env ids)

    if env_id is None:
        env_id = ORACLE_ENV if agent == "oracle" else DEFAULT_ENV
    elif agent == "oracle":
        env_kwargs.setdefault("observation", "oracle")
    if env_id.split(":")[-1] not in gym.registry:
        known = ", ".join(k for k in gym.registry if k.startswith("LRP"))
        raise InputError(f"--env: unknown env id {env_id!r}; known: {known}")
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


def run_episode(
    env: gym.Env, policy: Policy, seed: int, frames: list[np.ndarray] | None = None
) -> EpisodeResult:
    """Run one episode from ``env.reset(seed=seed)``; append rendered frames to ``frames``."""
    obs, info = env.reset(seed=seed)
    base = env.unwrapped
    dt = float(base.cfg.task.frame_period_s)
    waypoints = np.asarray(base.path.waypoints_m, dtype=float)
    true_xy = [np.asarray(info["true_pose"][:2], dtype=float)]
    est_xy = [np.asarray(info["est_pose"][:2], dtype=float)]
    errors, conv, confidence = [], [], []
    ret, collision, success, steps = 0.0, False, False, 0
    if frames is not None:
        frames.append(env.render())
    episode_start = np.ones(1, dtype=bool)
    state = None
    done = False
    while not done:
        action, state = policy.predict(obs, state, episode_start, deterministic=True)
        episode_start = np.zeros(1, dtype=bool)
        obs, reward, terminated, truncated, info = env.step(action)
        done = terminated or truncated
        steps += 1
        ret += float(reward)
        true_xy.append(np.asarray(info["true_pose"][:2], dtype=float))
        est_xy.append(np.asarray(info["est_pose"][:2], dtype=float))
        errors.append(info["position_error_m"])
        conv.append(info["converged"])
        confidence.append(info.get("localization_confidence", float(info["converged"])))
        collision |= bool(info["collision"])
        success |= bool(info["is_success"])
        if frames is not None:
            frames.append(env.render())
    txy = np.asarray(true_xy)
    return EpisodeResult(
        seed=seed,
        success=success,
        collision=collision,
        steps=steps,
        episode_return=ret,
        path_length_m=float(np.sum(np.linalg.norm(np.diff(txy, axis=0), axis=1))),
        time_to_goal_s=steps * dt if success else None,
        loc_error_m=np.asarray(errors, dtype=float),
        converged=np.asarray(conv, dtype=bool),
        confidence=np.asarray(confidence, dtype=float),
        cross_track_m=cross_track_m(txy[1:], waypoints),
        true_xy=txy,
        est_xy=np.asarray(est_xy),
        waypoints_m=waypoints,
    )


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


def evaluate(
    policy: Policy,
    env: gym.Env,
    n_episodes: int,
    seed: int = 0,
    gif_path: str | Path | None = None,
    progress: Any = None,
) -> dict[str, Any]:
    """Run ``n_episodes`` on seeds ``seed, seed + 1, ...`` and summarise them.

    Parameters
    ----------
    policy : Policy
        Any object with the SB3 ``predict`` signature.
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

    Returns
    -------
    dict
        :func:`summarize`'s metrics plus ``"per_episode"`` rows and ``"seed"``.
    """
    if n_episodes < 1:
        raise InputError(f"--episodes: must be at least 1, got {n_episodes}")
    results = []
    for i in range(n_episodes):
        frames: list[np.ndarray] | None = [] if (gif_path is not None and i == 0) else None
        res = run_episode(env, policy, seed + i, frames)
        if frames:
            write_gif(frames, gif_path, fps=env.metadata.get("render_fps", 4))
        results.append(res)
        if progress is not None:
            progress(res)
    summary = summarize(results)
    summary["seed"] = seed
    summary["per_episode"] = [r.row() for r in results]
    summary["_results"] = results  # for plotting; dropped before JSON output
    return summary


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


def summary_table(summary: dict[str, Any], title: str = "evaluation"):
    """A rich Table of the headline metrics."""
    from rich.table import Table

    def fmt(v, unit="", pct=False):
        if v is None:
            return "-"
        return f"{100 * v:.1f} %" if pct else f"{v:.3f}{unit}"

    t = Table(title=title)
    t.add_column("metric")
    t.add_column("value", justify="right")
    rows = [
        ("episodes", str(summary["episodes"])),
        ("success rate", fmt(summary["success_rate"], pct=True)),
        ("collision rate", fmt(summary["collision_rate"], pct=True)),
        ("mean time to goal", fmt(summary["mean_time_to_goal_s"], " s")),
        ("mean driven path length", fmt(summary["mean_path_length_m"], " m")),
        ("mean return", fmt(summary["mean_return"])),
        ("mean localisation error", fmt(summary["mean_loc_error_m"], " m")),
        ("  95th percentile", fmt(summary["p95_loc_error_m"], " m")),
        ("  max", fmt(summary["max_loc_error_m"], " m")),
        ("  mean once converged", fmt(summary["mean_loc_error_converged_m"], " m")),
        (f"time localised (< {LOCALISED_M:g} m)", fmt(summary["time_localised"], pct=True)),
        ("  median frames to first localised", fmt(summary["median_frames_to_localised"])),
        (
            "  confidently wrong (converged, > 0.3 m)",
            fmt(summary["confidently_wrong_rate"], pct=True),
        ),
        ("mean cross-track error", fmt(summary["mean_cross_track_m"], " m")),
        ("max cross-track error", fmt(summary["max_cross_track_m"], " m")),
    ]
    for k, v in rows:
        t.add_row(k, v)
    return t


__all__ = [
    "AGENTS",
    "DEFAULT_MODEL",
    "EpisodeResult",
    "Policy",
    "RandomPolicy",
    "SB3Policy",
    "cross_track_m",
    "evaluate",
    "load_ppo",
    "make_agent",
    "make_eval_env",
    "public",
    "run_episode",
    "summarize",
    "summary_table",
    "write_gif",
]
