"""``LRPRadarNav-v0``: drive a robot that localises itself with an FMCW radar and passive LRPs.

Each step applies the action to the differential-drive robot (true pose, collisions), produces
noisy odometry, runs one frame of the localisation stack (:mod:`lrp_gym.localization.stack`:
radar, LRP tracker, AMCL) and builds the observation from the *estimate*. The reward uses the
true pose: it is the task's score, not something the agent observes.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded

from lrp_gym.config import ScenarioConfig, load_scenario
from lrp_gym.envs.nav_batch import REWARD_TERMS, NavBatch
from lrp_gym.envs.task import WaypointPath
from lrp_gym.localization.factory import Localizer
from lrp_gym.localization.frame_result import FrameResult
from lrp_gym.localization.lut import LookupTable
from lrp_gym.localization.pose_estimate import PoseEstimate
from lrp_gym.localization.stack import LocalizationStack
from lrp_gym.perturbations import PerturbationSet
from lrp_gym.radar.detections import Detections
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.tracking.tracker import LrpTracker


def build_config(
    scenario: str | dict | ScenarioConfig | None = None,
    overrides: dict[str, Any] | None = None,
    *,
    radar_fidelity: str | None = None,
    observation: str | None = None,
    task_mode: str | None = None,
) -> ScenarioConfig:
    """The env's scenario: the paper room with sampled goals unless a scenario is given."""
    cfg = load_scenario("ipin2023" if scenario is None else scenario)
    patch: dict[str, Any] = {}
    if scenario is None and task_mode is None:
        task_mode = "goal"
    if task_mode is not None:
        patch["task"] = {"mode": task_mode}
    if radar_fidelity is not None:
        patch["radar"] = {"fidelity": radar_fidelity}
    if observation is not None:
        patch["env"] = {"observation": {"type": observation}}
    if patch:
        cfg = cfg.with_overrides(patch)
    if overrides:
        cfg = cfg.with_overrides(overrides)
    return cfg


class LRPRadarNavEnv(gym.Env):
    """Drive a robot to a goal on the pose it estimates from a 60 GHz radar and passive LRPs.

    The robot (a differential drive in a room with obstacles) never sees its true pose: every
    frame its radar measures the distances to the retroreflectors, an LRP tracker identifies
    them, AMCL turns them and the noisy wheel odometry into a pose estimate, and the agent acts
    on that estimate. Registered as ``LRPRadarNav-v0`` (signal-level radar),
    ``LRPRadarNavFast-v0`` (detections-level radar) and ``LRPRadarNavOracle-v0`` (observation
    from the true pose, an ablation); see :mod:`lrp_gym.envs`.

    **Action space**: ``Box(-1, 1, (2,), float32)``, (forward speed, turn rate) as fractions
    of ``robot.max_speed_mps`` (``robot.max_reverse_mps`` when negative) and
    ``robot.max_turn_rate_rps``; held for one frame of ``task.frame_period_s``.

    **Observation space** (``env.observation.type``, ``n = env.observation.n_waypoints``):
    ``estimated`` (default) is a float32 vector of ``10 + 2n + 4`` values built from the
    estimate only (:class:`~lrp_gym.envs.observations.EstimatedPoseObservation`):

    ==========  =====  ==============================================================
    index       count  content
    ==========  =====  ==============================================================
    0-1         2      estimated x / Lx, y / Ly (0..1 inside the room)
    2-3         2      cos, sin of the estimated heading
    4-6         3      std of x, y (m) and heading (rad), capped at 5
    7           1      1.0 once localisation has converged, else 0.0
    8           1      confidence in [0, 1] (``info["localization_confidence"]``)
    9           1      1 / ``info["n_modes"]`` (1: one mode; 0: no mode holds 5 %)
    10..10+2n   2n     next n waypoints (dx, dy) in the estimated robot frame (m)
    10+2n..+2   2      goal (dx, dy) in the estimated robot frame (m)
    last 2      2      previous action
    ==========  =====  ==============================================================

    ``oracle``: the same layout from the true pose (zero std, converged, confidence 1, one
    mode); ``dict``: the ``estimated`` content as a ``Dict`` space (``pose``, ``pose_std``,
    ``converged``, ``confidence``, ``unimodality``, ``waypoints``, ``goal``, ``last_action``).

    **Rewards** (weights ``task.rewards``), from the *true* pose: ``progress`` times the
    metres gained along the path (projection searched near the last one, so it cannot jump),
    ``-time`` per step, ``-collision`` on a collision and ``+goal`` on reaching the goal. Their
    split is ``info["rewards"]``.

    **Starting state**: ``task.mode: goal`` (the default without a scenario) draws a free
    start, a goal ``task.goal.min_distance_m`` to ``max_distance_m`` away with a free path
    (straight, or through one via point) and a heading within 90 degrees of the first leg;
    ``path`` starts at ``robot.start_pose`` on ``task.path`` (driven ``task.laps`` times when
    the path is a closed loop: a patrol). The localiser starts spread over
    the room (``localization.init: uniform``, global localisation) or around the true pose
    (``gaussian``). The first radar frame is taken at reset.

    **Episode end**: terminated on a collision (the motion is checked in ``env.substeps``
    sub-steps; the robot stops at the last free one) or when the goal is reached (within
    ``task.goal_tolerance_m`` and with the path's progress within two tolerances of its
    end). Truncated after ``task.max_episode_steps`` steps (default 200) by the env itself, so
    the scenario sets the limit (a patrol needs more); ``gym.make(..., max_episode_steps=N)``
    still adds gymnasium's ``TimeLimit`` on top.

    **Info**: true and estimated pose, position and heading errors, pose std, particles, ESS,
    detections, convergence, confidence, modes, ``suspect_reflectors`` (layout indices of the
    reflectors the localiser believes moved or missing, see
    :mod:`~lrp_gym.localization.reflector_monitor`), progress, path length, ``collision``,
    ``is_success`` and the reward terms.

    Parameters
    ----------
    scenario : path, scenario name, dict or ScenarioConfig, optional
        Default: the paper room (``ipin2023``) with a sampled start and goal per episode.
    overrides : dict, optional
        Nested config overrides, e.g. ``{"radar": {"noise": False}}``; ``perturbations``
        switch on robustness perturbations (:mod:`lrp_gym.perturbations`).
    radar_fidelity : {"signal", "detections"}, optional
        Shortcut for ``radar.fidelity``.
    observation : str, optional
        Shortcut for ``env.observation.type`` (``estimated``, ``oracle``, ``dict``).
    task_mode : {"goal", "path"}, optional
        Shortcut for ``task.mode``.
    render_mode : {"rgb_array", "human"}, optional

    **Version history**: v0, the first and current version. Within v0 the ``estimated``,
    ``oracle`` and ``dict`` observations gained the localisation confidence and the
    unimodality (1 / mode count) after the convergence flag (18 -> 20 values with the
    default three waypoints); models trained on the 18-value layout are refused.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 4}

    def __init__(
        self,
        scenario: str | dict | ScenarioConfig | None = None,
        overrides: dict[str, Any] | None = None,
        *,
        radar_fidelity: str | None = None,
        observation: str | None = None,
        task_mode: str | None = None,
        render_mode: str | None = None,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']}, got {render_mode!r}"
            )
        self.cfg = build_config(
            scenario,
            overrides,
            radar_fidelity=radar_fidelity,
            observation=observation,
            task_mode=task_mode,
        )
        # The batched core with one robot: the vector env runs the same code for N.
        self.core = NavBatch(self.cfg, 1)
        self.world = self.core.world
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.cfg.task.frame_period_s)}
        self.dt_s = self.core.dt_s
        self._obs_type = self.core.obs_type
        self.observation_space = self._obs_type.space
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self._radius_m = self.core.radius_m
        self._renderer = None
        self._done = False  # the episode has terminated; step() pays nothing until reset()

    # ------------------------------------------------------------------ the robot's state
    @property
    def stack(self) -> LocalizationStack:
        return self.core.stacks[0]

    @property
    def sensor(self) -> RadarSensor:
        return self.stack.sensor

    @property
    def tracker(self) -> LrpTracker:
        return self.stack.tracker

    @property
    def localizer(self) -> Localizer:
        return self.stack.localizer

    @property
    def lut(self) -> LookupTable | None:
        return self.stack.lut

    @property
    def perturbations(self) -> PerturbationSet | None:
        return self.core.perturbations[0]

    @property
    def pose(self) -> np.ndarray:
        """The true pose (x_m, y_m, theta_rad) (a copy; assign to move the robot)."""
        return self.core.pose[0].copy()

    @pose.setter
    def pose(self, value: np.ndarray) -> None:
        self.core.pose[0] = np.asarray(value, dtype=float)

    @property
    def path(self) -> WaypointPath | None:
        return self.core.paths[0]

    @property
    def frame(self) -> FrameResult | None:
        return self.core.frames[0]

    @property
    def estimate(self) -> PoseEstimate | None:
        """The pose estimate the observation is built from."""
        return self.core.estimates[0]

    @estimate.setter
    def estimate(self, value: PoseEstimate) -> None:
        self.core.estimates[0] = value

    @property
    def detections(self) -> Detections | None:
        frame = self.frame
        return None if frame is None else frame.detections

    @property
    def fingerprint(self) -> Fingerprint | None:
        frame = self.frame
        return None if frame is None else frame.fingerprint

    @property
    def _steps(self) -> int:
        return int(self.core.steps[0])

    # ------------------------------------------------------------------ gymnasium API
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        self._done = False
        self.core.reset_robot(0, self.np_random)
        return self._observe(), self._info(collided=False, reached=False, rewards=None)

    def step(self, action):
        if self.path is None:
            raise ResetNeeded("call reset() first: step() needs an episode")
        action = self._check_action(action)
        if self._done:
            # As gymnasium's own envs do: warn, and pay nothing for stepping past the end.
            gym.logger.warn(
                "step() called after the episode terminated; call reset() to start a new one"
            )
            info = self._info(collided=False, reached=False, rewards=None)
            return self._observe(), 0.0, True, False, info
        out = self.core.step(action[None, :], [self.np_random], _ROBOT_0)
        terminated = bool(out.terminated[0])
        self._done = terminated
        obs = self._observe()
        info = self.core.info(
            0, collided=out.collided[0], reached=out.reached[0], reward_terms=out.reward_terms[0]
        )
        if self.render_mode == "human":
            self.render()
        return obs, float(out.reward[0]), terminated, bool(out.truncated[0]), info

    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array'")
            return None
        if self.path is None:
            raise ResetNeeded("call reset() first: render() draws the current episode")
        if self._renderer is None:
            from lrp_gym.envs.rendering import Renderer

            self._renderer = Renderer(self.world, self.cfg.env.render_size_px, self.render_mode)
        return self._renderer.draw(self)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # ------------------------------------------------------------------ internals
    def _check_action(self, action) -> np.ndarray:
        return check_action(action)

    def _observe(self):
        if self.path is None:
            raise ResetNeeded("call reset() first: the env has no episode yet")
        return self.core.observe(0)

    def _info(self, *, collided: bool, reached: bool, rewards: dict | None) -> dict[str, Any]:
        if self.estimate is None:
            raise ResetNeeded("call reset() first: the env has no pose estimate yet")
        terms = None if rewards is None else np.array([rewards[k] for k in REWARD_TERMS])
        return self.core.info(0, collided=collided, reached=reached, reward_terms=terms)


_ROBOT_0 = np.zeros(1, dtype=np.intp)


def check_action(action) -> np.ndarray:
    """One robot's action as float (2,) clipped to [-1, 1] (ValueError naming ``action``)."""
    a = np.asarray(action, dtype=float)
    if a.shape != (2,):
        raise ValueError(f"action must have shape (2,) = (speed, turn), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"action must be finite, got {a.tolist()}")
    return np.clip(a, -1.0, 1.0)
