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
from lrp_gym.envs.observations import NavSnapshot, make_observation
from lrp_gym.envs.task import WaypointPath, sample_goal_task
from lrp_gym.localization.factory import Localizer
from lrp_gym.localization.lut import LookupTable
from lrp_gym.localization.pose_estimate import PoseEstimate
from lrp_gym.localization.stack import FrameResult, LocalizationStack
from lrp_gym.perturbations import FrameContext, PerturbationSet
from lrp_gym.radar.detections import Detections
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.tracking.tracker import LrpTracker
from lrp_gym.world import World, integrate_unicycle, noisy_odometry, wrap_angle

# Progress is searched for in a window around the last value so it cannot jump along the path.
_PROGRESS_BACK_M = 1.0
_PROGRESS_WINDOW_M = 3.0


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
    detections, convergence, confidence, modes, progress, path length, ``collision``,
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
        self.world = World.from_config(self.cfg)
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.cfg.task.frame_period_s)}
        self.dt_s = self.cfg.task.frame_period_s
        self.stack = LocalizationStack.from_config(self.world, self.cfg)
        # None when no perturbation is on: the hot path then pays one `is None` test per hook.
        perturbations = PerturbationSet.from_config(self.cfg.perturbations, self.world)
        self.perturbations: PerturbationSet | None = perturbations if len(perturbations) else None
        self._obs_type = make_observation(self.cfg.env.observation, self.world.room.size_m)
        self.observation_space = self._obs_type.space
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self._radius_m = self.world.robot.radius_m
        self._substep_dt = (
            self.dt_s * np.arange(1, self.cfg.env.substeps + 1) / self.cfg.env.substeps
        )
        self._renderer = None
        # Episode state (set in reset); the localisation state lives in self.stack.
        self.pose = np.zeros(3)
        self.path: WaypointPath | None = None
        self.frame: FrameResult | None = None
        self.estimate: PoseEstimate | None = None
        self.detections: Detections | None = None
        self.fingerprint: Fingerprint | None = None
        self._s_true = self._s_est = 0.0
        self._last_action = np.zeros(2)
        self._steps = 0
        self._done = False  # the episode has terminated; step() pays nothing until reset()

    # The stack's stages, for rendering and inspection.
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

    # ------------------------------------------------------------------ gymnasium API
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        rng = self.np_random
        task = self.cfg.task
        if task.mode == "path":
            self.pose = np.asarray(self.cfg.robot.start_pose, dtype=float)
            path = WaypointPath.from_points(task.driven_path())
        else:
            self.pose, path = sample_goal_task(self.world.room, task, self._radius_m + 0.1, rng)
        self.path = path
        self._last_action = np.zeros(2)
        self._steps = 0
        self._done = False
        known = self.pose if self.cfg.localization.init == "gaussian" else None
        self.stack.reset(rng, known)
        # The robot starts at the path's start: the first projections search only its first
        # metres. A global projection put a spread-out first estimate (uniform init) far along
        # the path, the observation's waypoints then pointed near the goal and the robot cut
        # across; a patrol also passes its start again at the end of every lap.
        laps = task.laps if task.mode == "path" else 1
        first_m = min(_PROGRESS_WINDOW_M, path.length_m / laps)
        self._s_true = path.project(self.pose[:2], 0.0, first_m)
        if self.perturbations is not None:
            # The radar may see another layout than the surveyed one the localiser uses.
            self.stack.set_radar_layout(self.perturbations.reset(self._frame_context(), rng))
        self._sense(np.zeros(3), np.zeros(2))
        self._s_est = path.project(self._estimate_now().pose[:2], 0.0, first_m)
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
        prev = self.pose
        velocity_xy, collided = self._drive(action)
        odo = noisy_odometry(self.world.odometry_noise, prev, self.pose, self.np_random)
        self._steps += 1
        if self.perturbations is not None:
            odo, moved = self.perturbations.move(self._frame_context(), odo, self.np_random)
            if moved is not None:
                self.pose = moved
        self._sense(odo, velocity_xy)
        self._last_action = action.astype(float)
        progress_m = self._update_progress()
        reached = self._goal_reached()
        reward, rewards = self._reward(progress_m, collided, reached)
        terminated = self._terminated(collided, reached)
        self._done = terminated
        truncated = not terminated and self._steps >= self.cfg.task.max_episode_steps
        obs = self._observe()
        info = self._info(collided=collided, reached=reached, rewards=rewards)
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, truncated, info

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

    # ------------------------------------------------------------------ task
    def _reward(
        self, progress_m: float, collided: bool, reached: bool
    ) -> tuple[float, dict[str, float]]:
        """The step's reward and its terms (weights ``task.rewards``)."""
        w = self.cfg.task.rewards
        rewards = {
            "progress": w.progress * progress_m,
            "time": -w.time,
            "collision": -w.collision if collided else 0.0,
            "goal": w.goal if reached else 0.0,
        }
        return float(sum(rewards.values())), rewards

    def _terminated(self, collided: bool, reached: bool) -> bool:
        """A collision or the goal ends the episode (the step limit truncates it instead)."""
        return collided or reached

    def _goal_reached(self) -> bool:
        """Within tolerance of the goal, having come along the path, not cut across to it."""
        tol = self.cfg.task.goal_tolerance_m
        path = self._episode_path()
        return bool(
            np.linalg.norm(self.pose[:2] - path.goal_m) <= tol
            and self._s_true >= path.length_m - 2.0 * tol
        )

    def _update_progress(self) -> float:
        """Project the true and estimated poses on the path; return the true progress made."""
        s_prev = self._s_true
        path = self._episode_path()
        self._s_true = path.project(
            self.pose[:2], max(s_prev - _PROGRESS_BACK_M, 0.0), _PROGRESS_WINDOW_M
        )
        self._s_est = path.project(
            self._estimate_now().pose[:2],
            max(self._s_est - _PROGRESS_BACK_M, 0.0),
            _PROGRESS_WINDOW_M,
        )
        return self._s_true - s_prev

    # ------------------------------------------------------------------ internals
    def _check_action(self, action) -> np.ndarray:
        a = np.asarray(action, dtype=float)
        if a.shape != (2,):
            raise ValueError(f"action must have shape (2,) = (speed, turn), got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action must be finite, got {a.tolist()}")
        return np.clip(a, -1.0, 1.0)

    def _drive(self, action: np.ndarray) -> tuple[np.ndarray, bool]:
        """Move the true pose for one frame; return (velocity_xy, collided)."""
        lim = self.world.robot
        speed = action[0] * (lim.max_speed_mps if action[0] >= 0 else lim.max_reverse_mps)
        turn = action[1] * lim.max_turn_rate_rps
        # Sub-steps catch collisions that a single end-of-frame check would tunnel through.
        track = integrate_unicycle(self.pose, speed, turn, self._substep_dt)
        free = self.world.room.free(track[:, :2], self._radius_m)
        if free.all():
            self.pose = track[-1]
            return speed * np.array([np.cos(self.pose[2]), np.sin(self.pose[2])]), False
        first_bad = int(np.argmin(free))
        self.pose = track[first_bad - 1] if first_bad > 0 else self.pose.copy()
        return np.zeros(2), True

    def _sense(self, odometry: np.ndarray, velocity_xy: np.ndarray) -> None:
        """One frame of the localisation stack at the true pose, with the perturbations' hooks."""
        rng = self.np_random
        pert = self.perturbations
        hooks: dict[str, Any] = {}
        if pert is not None:
            ctx = self._frame_context()
            hidden, extra = pert.radar_inputs(ctx, rng)
            hooks = {"hidden": hidden, "extra_scatterers": extra}
            hooks["filter_detections"] = lambda det: pert.filter_detections(ctx, det, rng)
        frame = self.stack.step(self.pose, velocity_xy, odometry, rng, **hooks)
        self.frame = frame
        self.detections, self.fingerprint = frame.detections, frame.fingerprint
        self.estimate = frame.estimate

    def _frame_context(self) -> FrameContext:
        sensor = self.stack.sensor
        return FrameContext(
            self._steps, self.pose, self.world, sensor.world.layout, self.dt_s, sensor
        )

    def _episode_path(self) -> WaypointPath:
        if self.path is None:
            raise ResetNeeded("call reset() first: the env has no episode yet")
        return self.path

    def _estimate_now(self) -> PoseEstimate:
        if self.estimate is None:
            raise ResetNeeded("call reset() first: the env has no pose estimate yet")
        return self.estimate

    def _snapshot(self) -> NavSnapshot:
        est = self._estimate_now()
        return NavSnapshot(
            est_pose=est.pose,
            est_std=est.std,
            converged=est.converged,
            confidence=est.confidence,
            n_modes=est.n_modes,
            true_pose=self.pose,
            path=self._episode_path(),
            s_est_m=self._s_est,
            s_true_m=self._s_true,
            last_action=self._last_action,
            room_size_m=self.world.room.size_m,
        )

    def _observe(self):
        return self._obs_type.observe(self._snapshot())

    def _info(self, *, collided: bool, reached: bool, rewards: dict | None) -> dict[str, Any]:
        est = self._estimate_now()
        err = est.pose[:2] - self.pose[:2]
        return {
            "true_pose": self.pose.copy(),
            "est_pose": est.pose.copy(),
            "position_error_m": float(np.hypot(*err)),
            "heading_error_rad": float(np.abs(wrap_angle(est.pose[2] - self.pose[2]))),
            "pose_std": est.std,
            "n_particles": int(est.n_particles),
            "ess": float(est.ess),
            "n_detections": 0 if self.detections is None else len(self.detections),
            "converged": bool(est.converged),
            "localization_confidence": float(est.confidence),
            "n_modes": int(est.n_modes),
            "progress_m": self._s_true,
            "path_length_m": self._episode_path().length_m,
            "collision": collided,
            "is_success": reached,
            "rewards": rewards or {"progress": 0.0, "time": 0.0, "collision": 0.0, "goal": 0.0},
        }
