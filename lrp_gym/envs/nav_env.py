"""``LRPRadarNav-v0``: drive a robot that localises itself with an FMCW radar and passive LRPs.

Each step applies the action to the differential-drive robot (true pose, collisions), produces
noisy odometry, runs one radar frame (signal-level or detections fidelity), the LRP tracker and
AMCL, and builds the observation from the *estimate*. The reward uses the true pose: it is the
task's score, not something the agent observes.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded

from lrp_gym.config import ScenarioConfig, load_scenario
from lrp_gym.envs.observations import NavSnapshot, make_observation
from lrp_gym.envs.task import WaypointPath, sample_goal_task
from lrp_gym.localization.estimate import PoseEstimate
from lrp_gym.localization.factory import make_localizer
from lrp_gym.localization.lut import LookupTable
from lrp_gym.localization.pipeline import track_and_localize
from lrp_gym.perturbations import FrameContext, PerturbationSet
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.tracking.motion import EgoMotion
from lrp_gym.tracking.tracker import LrpTracker
from lrp_gym.world import World, integrate_unicycle, odometry_delta, wrap_angle

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
    """Closed-loop navigation on the radar/AMCL pose estimate.

    Parameters
    ----------
    scenario : path, scenario name, dict or ScenarioConfig, optional
        Default: the paper room (``ipin2023``) with a sampled start and goal per episode.
    overrides : dict, optional
        Nested config overrides, e.g. ``{"radar": {"noise": False}}``.
    radar_fidelity : {"signal", "detections"}, optional
        Shortcut for ``radar.fidelity``.
    observation : str, optional
        Shortcut for ``env.observation.type`` (``estimated``, ``oracle``, ``dict``).
    task_mode : {"goal", "path"}, optional
        Shortcut for ``task.mode``.
    render_mode : {"rgb_array", "human"}, optional

    Action: ``Box(-1, 1, (2,), float32)`` = (forward speed, turn rate) as fractions of the
    robot's limits (negative speed reverses, up to ``robot.max_reverse_mps``).
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
        self.sensor = RadarSensor(self.world, self.cfg.radar)
        self._surveyed_sensor = self.sensor
        # None when no perturbation is on: the hot path then pays one `is None` test per hook.
        perturbations = PerturbationSet.from_config(self.cfg.perturbations, self.world)
        self.perturbations: PerturbationSet | None = perturbations if len(perturbations) else None
        self.tracker = LrpTracker.from_world(self.world, self.cfg.tracking)
        loc = self.cfg.localization
        self.localizer = make_localizer(self.world, loc)
        self.lut = (
            LookupTable(self.world, loc.lut_resolution_m, loc.lut_grid_m)
            if loc.method == "lut"
            else None
        )
        self._obs_type = make_observation(self.cfg.env.observation, self.world.room.size_m)
        self.observation_space = self._obs_type.space
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        lim = self.world.robot
        self._radius_m = lim.radius_m
        self._substep_dt = (
            self.dt_s * np.arange(1, self.cfg.env.substeps + 1) / self.cfg.env.substeps
        )
        self._renderer = None
        # Episode state (set in reset).
        self.pose = np.zeros(3)
        self.path: WaypointPath | None = None
        self.estimate: PoseEstimate | None = None
        self._amcl_estimate: PoseEstimate | None = None  # the tracker's prior, also in LUT mode
        self.detections = None
        self.fingerprint = None
        self._s_true = self._s_est = 0.0
        self._last_action = np.zeros(2)
        self._steps = 0
        self._done = False  # the episode has terminated; step() pays nothing until reset()

    # ------------------------------------------------------------------ gymnasium API
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        rng = self.np_random
        task = self.cfg.task
        if task.mode == "path":
            self.pose = np.asarray(self.cfg.robot.start_pose, dtype=float)
            self.path = WaypointPath.from_points(np.asarray(task.path))
        else:
            self.pose, self.path = sample_goal_task(
                self.world.room, task, self._radius_m + 0.1, rng
            )
        self._last_action = np.zeros(2)
        self._steps = 0
        self._done = False
        self.tracker.reset()
        self.estimate = self._amcl_estimate = None
        known = self.pose if self.cfg.localization.init == "gaussian" else None
        self.localizer.reset(rng, pose=known)
        self._s_true = self.path.project(self.pose[:2])
        if self.perturbations is not None:
            # The radar may see another layout than the surveyed one the localiser uses.
            self.sensor = self._surveyed_sensor
            layout = self.perturbations.reset(self._frame_context(), rng)
            if layout is not self.world.layout:
                self.sensor = RadarSensor(replace(self.world, layout=layout), self.cfg.radar)
        self._sense(np.zeros(3), np.zeros(2))
        self._s_est = self.path.project(self.estimate.pose[:2])
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
        lim = self.world.robot
        speed = action[0] * (lim.max_speed_mps if action[0] >= 0 else lim.max_reverse_mps)
        turn = action[1] * lim.max_turn_rate_rps
        # Sub-steps catch collisions that a single end-of-frame check would tunnel through.
        track = integrate_unicycle(self.pose, speed, turn, self._substep_dt)
        free = self.world.room.free(track[:, :2], self._radius_m)
        collided = not bool(free.all())
        prev = self.pose
        if collided:
            first_bad = int(np.argmin(free))
            new_pose = track[first_bad - 1] if first_bad > 0 else prev.copy()
            velocity_xy = np.zeros(2)
        else:
            new_pose = track[-1]
            velocity_xy = speed * np.array([np.cos(new_pose[2]), np.sin(new_pose[2])])
        self.pose = new_pose
        odo = self.world.odometry_noise.sample(odometry_delta(prev, new_pose), (), self.np_random)
        self._steps += 1
        if self.perturbations is not None:
            odo, moved = self.perturbations.move(self._frame_context(), odo, self.np_random)
            if moved is not None:
                self.pose = moved
        self._sense(odo, velocity_xy)
        self._last_action = action.astype(float)

        s_prev = self._s_true
        self._s_true = self.path.project(
            self.pose[:2], max(s_prev - _PROGRESS_BACK_M, 0.0), _PROGRESS_WINDOW_M
        )
        self._s_est = self.path.project(
            self.estimate.pose[:2], max(self._s_est - _PROGRESS_BACK_M, 0.0), _PROGRESS_WINDOW_M
        )
        # The goal counts once reached along the path, not by cutting across to it.
        tol = self.cfg.task.goal_tolerance_m
        reached = bool(
            np.linalg.norm(self.pose[:2] - self.path.goal_m) <= tol
            and self._s_true >= self.path.length_m - 2.0 * tol
        )
        w = self.cfg.task.rewards
        rewards = {
            "progress": w.progress * (self._s_true - s_prev),
            "time": -w.time,
            "collision": -w.collision if collided else 0.0,
            "goal": w.goal if reached else 0.0,
        }
        reward = float(sum(rewards.values()))
        terminated = collided or reached
        self._done = terminated
        obs = self._observe()
        info = self._info(collided=collided, reached=reached, rewards=rewards)
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, False, info

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
        a = np.asarray(action, dtype=float)
        if a.shape != (2,):
            raise ValueError(f"action must have shape (2,) = (speed, turn), got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action must be finite, got {a.tolist()}")
        return np.clip(a, -1.0, 1.0)

    def _sense(self, odometry: np.ndarray, velocity_xy: np.ndarray) -> None:
        """One radar frame, tracker update and localisation update."""
        rng = self.np_random
        pert = self.perturbations
        if pert is None:
            self.detections = self.sensor.measure(self.pose, velocity_xy, rng)
        else:
            ctx = self._frame_context()
            hidden, extra = pert.radar_inputs(ctx, rng)
            det = self.sensor.measure(
                self.pose, velocity_xy, rng, hidden=hidden, extra_scatterers=extra
            )
            self.detections = pert.filter_detections(ctx, det, rng)
        ego = EgoMotion.from_velocity(velocity_xy, self.pose[2], odometry)
        self.fingerprint, est = track_and_localize(
            self.world,
            self.tracker,
            self.localizer,
            self.detections,
            self.dt_s,
            ego,
            self._amcl_estimate,
            rng,
            measurements=self.cfg.localization.measurements,
        )
        self._amcl_estimate = est
        if self.lut is not None:
            lut_est = self.lut.query(self.fingerprint)
            # The table knows no heading: keep AMCL's.
            pose = np.array([lut_est.pose[0], lut_est.pose[1], est.pose[2]])
            est = PoseEstimate(
                pose, lut_est.covariance, 0, 0.0, lut_est.converged, float(lut_est.converged), 1
            )
        self.estimate = est

    def _frame_context(self) -> FrameContext:
        return FrameContext(
            self._steps, self.pose, self.world, self.sensor.world.layout, self.dt_s, self.sensor
        )

    def _snapshot(self) -> NavSnapshot:
        return NavSnapshot(
            est_pose=self.estimate.pose,
            est_std=self.estimate.std,
            converged=self.estimate.converged,
            true_pose=self.pose,
            path=self.path,
            s_est_m=self._s_est,
            s_true_m=self._s_true,
            last_action=self._last_action,
            room_size_m=self.world.room.size_m,
        )

    def _observe(self):
        return self._obs_type.observe(self._snapshot())

    def _info(self, *, collided: bool, reached: bool, rewards: dict | None) -> dict[str, Any]:
        est = self.estimate
        err = est.pose[:2] - self.pose[:2]
        return {
            "true_pose": self.pose.copy(),
            "est_pose": est.pose.copy(),
            "position_error_m": float(np.hypot(*err)),
            "heading_error_rad": float(abs(wrap_angle(est.pose[2] - self.pose[2]))),
            "pose_std": est.std,
            "n_particles": int(est.n_particles),
            "ess": float(est.ess),
            "n_detections": len(self.detections),
            "converged": bool(est.converged),
            "localization_confidence": float(est.confidence),
            "n_modes": int(est.n_modes),
            "progress_m": self._s_true,
            "path_length_m": self.path.length_m,
            "collision": collided,
            "is_success": reached,
            "rewards": rewards or {"progress": 0.0, "time": 0.0, "collision": 0.0, "goal": 0.0},
        }
