"""The agents by name: pure pursuit, PPO (with its VecNormalize statistics), random, and pure
pursuit on the true pose (oracle), each a :class:`~lrp_gym.experiments.episodes.Policy` that
:func:`lrp_gym.experiments.episodes.run_episodes` drives; plus the metrics table.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from agents.pure_pursuit import PurePursuitPolicy
from lrp_gym.experiments.episodes import Policy
from lrp_gym.localization.metrics import LOCALISED_M

AGENTS = ("pure-pursuit", "ppo", "random", "oracle")
#: The agents that take pure pursuit's settings (``options`` of :func:`make_agent`).
CONFIGURABLE_AGENTS = ("pure-pursuit", "oracle")
MODELS_DIR = Path(__file__).resolve().parent / "models"
DEFAULT_MODEL = MODELS_DIR / "ppo_lrp_nav.zip"


class RandomPolicy:
    """Uniform random actions from a seeded generator (a lower bound)."""

    def __init__(self, action_space: gym.Space, rng: np.random.Generator) -> None:
        if not isinstance(action_space, gym.spaces.Box):
            raise ValueError(f"action_space: random actions need a Box, got {action_space}")
        self.low, self.high = action_space.low, action_space.high
        self.rng = rng

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        shape = np.shape(observation)[:-1] + self.low.shape
        return self.rng.uniform(self.low, self.high, size=shape).astype(np.float32), state

    def reset(self) -> None:
        """Stateless apart from the generator, which runs on across episodes."""

    def act(self, observation: np.ndarray) -> np.ndarray:
        return self.predict(observation)[0]


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

    def reset(self) -> None:
        """The feed-forward PPO policy keeps no state between steps."""

    def act(self, observation: np.ndarray) -> np.ndarray:
        return self.predict(observation, deterministic=True)[0]


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
    ValueError
        Naming ``model_path``: the file is missing, is not a readable PPO model, was trained for other spaces, or its
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
        raise ValueError(f"model_path: no such model file: {path}{hint}")
    model_io.read_zip_data(path)  # a clear message for a non-model before the statistics
    stats = model_io.find_stats(path)
    if stats is None:
        pkl = model_io.find_stats(path, ".pkl")
        raise ValueError(
            f"model_path: {path} has no normalisation statistics ({model_io.stats_path_for(path).name} "
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
    agent: str,
    env: gym.Env,
    model_path: str | Path | None = None,
    seed: int = 0,
    options: dict[str, Any] | None = None,
) -> Policy:
    """The policy for an agent name (see :data:`AGENTS`) acting in ``env``; ``options``, pure
    pursuit's settings (:func:`agents.pure_pursuit.parse_options`), for pure-pursuit and
    oracle only."""
    if options and agent not in CONFIGURABLE_AGENTS:
        raise ValueError(f"options: agent {agent!r} takes no options")
    if agent in CONFIGURABLE_AGENTS:
        return PurePursuitPolicy.from_env(env, **(options or {}))
    if agent == "random":
        return RandomPolicy(env.action_space, np.random.default_rng(seed))
    if agent == "ppo":
        return load_ppo(model_path, (env.observation_space, env.action_space))
    raise ValueError(f"agent: unknown agent {agent!r}; choose one of {', '.join(AGENTS)}")


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


def reliability_table(rows: list[dict[str, Any]], title: str = "confidence reliability"):
    """A rich Table of :func:`lrp_gym.localization.metrics.reliability`'s bins: per band of
    the localisation confidence, its steps, the mean confidence (a claim: wrong at most
    1 - c of the time) and the shares localised and wrong (> 0.3 m)."""
    from rich.table import Table

    t = Table(title=title)
    for name in ("confidence", "steps", "mean", "localised", "wrong (> 0.3 m)", "claim 1 - c"):
        t.add_column(name, justify="right")
    for r in rows:
        if not r["steps"]:
            continue
        wrong = r.get("wrong_share")
        t.add_row(
            f"{r['lo']:g}-{r['hi']:g}",
            str(r["steps"]),
            f"{r['mean_confidence']:.3f}",
            f"{100 * r['localised_share']:.1f} %",
            "-" if wrong is None else f"{100 * wrong:.1f} %",
            f"{100 * (1 - r['mean_confidence']):.1f} %",
        )
    return t


__all__ = [
    "AGENTS",
    "DEFAULT_MODEL",
    "RandomPolicy",
    "SB3Policy",
    "load_ppo",
    "make_agent",
    "reliability_table",
    "summary_table",
]
