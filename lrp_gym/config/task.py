"""Schema of the layout search, the task (path or sampled goals), rewards and observation."""

from __future__ import annotations

import sys
from typing import Annotated, Literal

import numpy as np
from pydantic import (
    Field,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from lrp_gym.config.base import NonNegFloat, PositiveFloat, Strict, Vec2


class PlacementConfig(Strict):
    grid_m: PositiveFloat = 0.025
    clearance_m: NonNegFloat = 0.0
    separation_m: PositiveFloat = 0.3
    tolerance_m: PositiveFloat | None = None
    min_spacing_m: NonNegFloat = 1.0
    wall_distance_m: NonNegFloat = 0.3
    constraint_tolerance_m: NonNegFloat = 0.1
    # Layout search: every candidate is scored on the coarse search grid, the best
    # ``refine_top`` again on ``grid_m``.
    candidates: Annotated[int, Field(ge=1)] = 500
    search_grid_m: PositiveFloat = 0.1
    refine_top: Annotated[int, Field(ge=1)] = 8


class GoalTaskConfig(Strict):
    """Sampled goal tasks: start-to-goal distance bounds (checked against the room)."""

    min_distance_m: PositiveFloat = 1.0
    max_distance_m: PositiveFloat = 4.0
    waypoint_spacing_m: PositiveFloat = 0.5


class RewardConfig(Strict):
    progress: NonNegFloat = 1.0
    time: NonNegFloat = 0.01
    collision: NonNegFloat = 5.0
    goal: NonNegFloat = 5.0


#: Observation types shipped in ``lrp_gym.envs.observations`` (more may be registered there).
OBSERVATION_TYPES = ("estimated", "oracle", "dict")


class ObservationConfig(Strict):
    """Which observation type the env builds (see ``lrp_gym.envs.observations``)."""

    type: str = "estimated"
    n_waypoints: Annotated[int, Field(ge=1, le=20)] = 3

    @field_validator("type")
    @classmethod
    def _registered(cls, v: str) -> str:
        # The registry is consulted only once loaded (it imports this module); user types are
        # registered there before a scenario names them.
        obs = sys.modules.get("lrp_gym.envs.observations")
        known = sorted(set(OBSERVATION_TYPES) | set(getattr(obs, "OBSERVATION_TYPES", {})))
        if v not in known:
            raise PydanticCustomError(
                "choice",
                "unknown observation type {v}; known: {known}",
                {"v": repr(v), "known": ", ".join(known)},
            )
        return v


class EnvConfig(Strict):
    """Environment settings: observation type, collision sub-steps, render size."""

    observation: ObservationConfig = ObservationConfig()
    substeps: Annotated[int, Field(ge=1, le=50)] = 4
    render_size_px: Annotated[int, Field(ge=64, le=2048)] = 480


#: Default step limit of an episode (the patrol scenarios set their own, see ``max_episode_steps``).
DEFAULT_MAX_EPISODE_STEPS = 200
#: The last waypoint of a closed loop lies within this distance of the first (metres).
LOOP_CLOSURE_M = 1e-3


class TaskConfig(Strict):
    """The task: a fixed path (driven ``laps`` times) or sampled goals, the frame period, the
    goal tolerance, rewards, and the step limit after which an episode is truncated."""

    mode: Literal["path", "goal"] = "path"
    path: list[Vec2] = []
    # A closed path (last waypoint = first) driven this many times in one episode: a patrol, long
    # enough that a perturbation happening once is not censored by the episode's end.
    laps: Annotated[int, Field(ge=1, le=1000)] = 1
    # The env truncates an episode after this many steps (gymnasium's TimeLimit, owned by the
    # scenario so a long patrol is not cut short).
    max_episode_steps: Annotated[int, Field(ge=1, le=1_000_000)] = DEFAULT_MAX_EPISODE_STEPS
    frame_period_s: PositiveFloat = 0.25
    goal_tolerance_m: PositiveFloat = 0.25
    goal: GoalTaskConfig = GoalTaskConfig()
    rewards: RewardConfig = RewardConfig()

    @model_validator(mode="after")
    def _path_needed(self) -> TaskConfig:
        if self.mode == "path" and len(self.path) < 2:
            raise PydanticCustomError("path", "mode 'path' needs at least 2 waypoints in path", {})
        return self

    @property
    def closed(self) -> bool:
        """Whether ``path`` is a closed loop (its last waypoint is its first)."""
        return len(self.path) >= 2 and bool(
            np.hypot(*np.subtract(self.path[-1], self.path[0])) <= LOOP_CLOSURE_M
        )

    def driven_path(self) -> np.ndarray:
        """The waypoints (K, 2) one episode drives: ``path``, repeated ``laps`` times."""
        pts = np.asarray(self.path, dtype=float).reshape(-1, 2)
        if self.laps == 1:
            return pts
        return np.concatenate([pts] + [pts[1:]] * (self.laps - 1))
