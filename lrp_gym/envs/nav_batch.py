"""The navigation task for a batch of robots: the one implementation behind every env class.

:class:`NavBatch` holds N robots in one room (one scenario): their true poses, progress and
episode counters as arrays, and one localisation stack each (shared map, radar model and
look-up table; own tracks and particles). Its :meth:`NavBatch.step` moves the robots that are
stepped with array calls (kinematics, sub-step collision checks, rewards, termination) and runs
one radar frame per robot. ``LRPRadarNavEnv`` is a batch of one; the vector env
(:mod:`lrp_gym.envs.vector_env`) and the Stable-Baselines3 adapter (:mod:`lrp_gym.envs.sb3`)
are batches of N.

Every random draw of robot ``i`` comes from robot ``i``'s own generator (or a child of it spawned
at reset), in the same order as a batch of one would make them: robot ``i`` of a batch reset
with seed ``s`` follows exactly the trajectory of a single env reset with seed ``s``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from lrp_gym.config import ScenarioConfig
from lrp_gym.envs.observations import NavSnapshot, ObservationType, make_observation
from lrp_gym.envs.task import WaypointPath, sample_goal_task
from lrp_gym.localization.frame_result import FrameResult
from lrp_gym.localization.pose_estimate import PoseEstimate
from lrp_gym.localization.stack import LocalizationStack
from lrp_gym.perturbations import FrameContext, PerturbationSet
from lrp_gym.world import World, integrate_unicycle, noisy_odometry, wrap_angle

# Progress is searched for in a window around the last value so it cannot jump along the path.
_PROGRESS_BACK_M = 1.0
_PROGRESS_WINDOW_M = 3.0
# The estimated progress advances at most by the odometry's distance plus this per frame.
_PROGRESS_SLACK_M = 0.25

#: The reward terms of ``info["rewards"]`` (all zero at reset).
REWARD_TERMS = ("progress", "time", "collision", "goal")


@dataclass(frozen=True)
class BatchStep:
    """What one step of the stepped robots gave (arrays over the stepped robots, in order)."""

    robots: np.ndarray  # (K,) indices of the stepped robots
    reward: np.ndarray  # (K,)
    terminated: np.ndarray  # (K,) bool: collision or goal
    truncated: np.ndarray  # (K,) bool: step limit, not terminated
    collided: np.ndarray  # (K,) bool
    reached: np.ndarray  # (K,) bool
    reward_terms: np.ndarray  # (K, 4) the terms of REWARD_TERMS


class NavBatch:
    """N robots of one scenario, their localisation stacks and the task, as arrays.

    Parameters
    ----------
    cfg : ScenarioConfig
        The validated scenario (room, layout, radar, localisation, task, perturbations).
    num_robots : int
        Batch size N (>= 1).

    Attributes
    ----------
    pose : ndarray (N, 3)
        True poses (x_m, y_m, theta_rad).
    s_true_m, s_est_m : ndarray (N,)
        Progress of the true and the estimated pose along each robot's path.
    last_action : ndarray (N, 2)
        The previous (clipped) action of each robot.
    steps : ndarray (N,) int
        Steps taken in the current episode.
    paths : list of WaypointPath
        Each robot's path of the current episode (None before its first reset).
    frames : list of FrameResult
        Each robot's last radar frame through its stack.
    estimates : list of PoseEstimate
        The pose each robot's observation is built from (the stack's estimate).
    """

    def __init__(self, cfg: ScenarioConfig, num_robots: int) -> None:
        if int(num_robots) < 1:
            raise ValueError(f"num_envs must be at least 1, got {num_robots}")
        n = int(num_robots)
        self.cfg = cfg
        self.num_robots = n
        self.world = World.from_config(cfg)
        self.dt_s = float(cfg.task.frame_period_s)
        first = LocalizationStack.from_config(self.world, cfg)
        # One stack per robot; the map, radar model, grids and look-up table are shared.
        self.stacks = [first] + [first.spawn() for _ in range(n - 1)]
        # None when no perturbation is on: the hot path then pays one `is None` test per hook.
        self.perturbations = [self._perturbation_set() for _ in range(n)]
        # Sensing (radar, odometry noise) and perturbations draw from two children of the
        # robot's generator, spawned at reset: one seed gives the same frames and kidnaps
        # whatever the localiser draws, until two settings' paths part (paired comparisons).
        self.sensing_rngs: list[np.random.Generator | None] = [None] * n
        self.perturbation_rngs: list[np.random.Generator | None] = [None] * n
        self.obs_type: ObservationType = make_observation(
            cfg.env.observation, self.world.room.size_m
        )
        self.radius_m = float(self.world.robot.radius_m)
        self._substep_dt = self.dt_s * np.arange(1, cfg.env.substeps + 1) / cfg.env.substeps
        self.pose = np.zeros((n, 3))
        self.s_true_m = np.zeros(n)
        self.s_est_m = np.zeros(n)
        self.last_action = np.zeros((n, 2))
        self.steps = np.zeros(n, dtype=np.int64)
        self.paths: list[WaypointPath | None] = [None] * n
        self.frames: list[FrameResult | None] = [None] * n
        self.estimates: list[PoseEstimate | None] = [None] * n

    def _perturbation_set(self) -> PerturbationSet | None:
        pert = PerturbationSet.from_config(self.cfg.perturbations, self.world)
        return pert if len(pert) else None

    # ------------------------------------------------------------------ episodes
    def reset_robot(self, i: int, rng: np.random.Generator) -> None:
        """Start robot ``i``'s next episode: start pose, path, a fresh stack, the first frame."""
        task = self.cfg.task
        if task.mode == "path":
            pose = np.asarray(self.cfg.robot.start_pose, dtype=float)
            path = WaypointPath.from_points(task.driven_path())
        else:
            pose, path = sample_goal_task(self.world.room, task, self.radius_m + 0.1, rng)
        self.pose[i] = pose
        self.paths[i] = path
        self.last_action[i] = 0.0
        self.steps[i] = 0
        known = self.pose[i].copy() if self.cfg.localization.init == "gaussian" else None
        stack = self.stacks[i]
        stack.reset(rng, known)
        self.sensing_rngs[i], self.perturbation_rngs[i] = rng.spawn(2)
        # The robot starts at the path's start: the first projections search only its first
        # metres. A global projection put a spread-out first estimate (uniform init) far along
        # the path, the observation's waypoints then pointed near the goal and the robot cut
        # across; a patrol also passes its start again at the end of every lap.
        laps = task.laps if task.mode == "path" else 1
        first_m = min(_PROGRESS_WINDOW_M, path.length_m / laps)
        self.s_true_m[i] = path.project(self.pose[i, :2], 0.0, first_m)
        pert = self.perturbations[i]
        if pert is not None:
            # The radar may see another layout than the surveyed one the localiser uses.
            stack.set_radar_layout(pert.reset(self.frame_context(i), self.perturbation_rngs[i]))
        self._sense(i, np.zeros(3), np.zeros(2), rng)
        self.s_est_m[i] = path.project(self.estimate(i).pose[:2], 0.0, first_m)

    def step(
        self, actions: np.ndarray, rngs: Sequence[np.random.Generator], robots: np.ndarray
    ) -> BatchStep:
        """Step ``robots`` (K,) with their clipped ``actions`` (K, 2); ``rngs`` has one
        generator per robot of the batch (N). Robots not listed do not move."""
        robots = np.asarray(robots, dtype=np.intp)
        prev = self.pose[robots]
        new_pose, velocity_xy, collided = self._drive(prev, actions)
        self.pose[robots] = new_pose
        self.steps[robots] += 1
        driven_m = np.zeros(len(robots))
        for k, i in enumerate(robots):
            odo = noisy_odometry(
                self.world.odometry_noise, prev[k], self.pose[i], self.sensing_rngs[i]
            )
            pert = self.perturbations[i]
            if pert is not None:
                odo, moved = pert.move(self.frame_context(i), odo, self.perturbation_rngs[i])
                if moved is not None:
                    self.pose[i] = moved
            driven_m[k] = abs(float(odo[1]))
            self._sense(i, odo, velocity_xy[k], rngs[i])
        self.last_action[robots] = actions
        progress_m = np.array([self._update_progress(i, d) for i, d in zip(robots, driven_m)])
        reached = np.array([self._goal_reached(i) for i in robots], dtype=bool)
        terms = self._reward_terms(progress_m, collided, reached)
        terminated = collided | reached
        truncated = ~terminated & (self.steps[robots] >= self.cfg.task.max_episode_steps)
        reward = terms.sum(axis=1)
        return BatchStep(robots, reward, terminated, truncated, collided, reached, terms)

    # ------------------------------------------------------------------ task
    def _reward_terms(
        self, progress_m: np.ndarray, collided: np.ndarray, reached: np.ndarray
    ) -> np.ndarray:
        """The reward terms (K, 4) in the order of :data:`REWARD_TERMS` (weights
        ``task.rewards``): metres gained along the path, time, collision, goal."""
        w = self.cfg.task.rewards
        k = len(progress_m)
        return np.column_stack(
            [
                w.progress * progress_m,
                np.full(k, -w.time),
                np.where(collided, -w.collision, 0.0),
                np.where(reached, w.goal, 0.0),
            ]
        )

    def _goal_reached(self, i: int) -> bool:
        """Within tolerance of the goal, having come along the path, not cut across to it."""
        tol = self.cfg.task.goal_tolerance_m
        path = self.path(i)
        return bool(
            np.linalg.norm(self.pose[i, :2] - path.goal_m) <= tol
            and self.s_true_m[i] >= path.length_m - 2.0 * tol
        )

    def _update_progress(self, i: int, driven_m: float) -> float:
        """Project robot ``i``'s true and estimated poses on its path; the true progress made.

        The estimated progress (what the observation's waypoints follow) gains at most the
        distance the odometry reports, ``driven_m``, plus a slack: a wrong estimate for a few
        frames (a global start's wrong mode, recovery particles) would otherwise carry it
        two metres a frame along the path, and on a patrol a whole lap ahead of the robot,
        which then stopped a lap early.
        """
        s_prev = float(self.s_true_m[i])
        path = self.path(i)
        self.s_true_m[i] = path.project(
            self.pose[i, :2], max(s_prev - _PROGRESS_BACK_M, 0.0), _PROGRESS_WINDOW_M
        )
        s_est = float(self.s_est_m[i])
        back = min(s_est, _PROGRESS_BACK_M)
        self.s_est_m[i] = path.project(
            self.estimate(i).pose[:2], s_est - back, back + driven_m + _PROGRESS_SLACK_M
        )
        return float(self.s_true_m[i]) - s_prev

    # ------------------------------------------------------------------ robot and sensing
    def _drive(
        self, pose: np.ndarray, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Move poses (K, 3) for one frame: (new poses, velocity_xy (K, 2), collided (K,)).

        The motion is checked at ``env.substeps`` sub-steps, so that a fast robot cannot
        tunnel through a thin obstacle; a robot that would collide stops at its last free
        sub-step, with zero velocity.
        """
        lim = self.world.robot
        forward = actions[:, 0]
        speed = forward * np.where(forward >= 0, lim.max_speed_mps, lim.max_reverse_mps)
        turn = actions[:, 1] * lim.max_turn_rate_rps
        # (K, S, 3): every robot at every sub-step.
        track = integrate_unicycle(
            pose[:, None, :], speed[:, None], turn[:, None], self._substep_dt
        )
        k, s = track.shape[:2]
        free = self.world.room.free(track[..., :2].reshape(-1, 2), self.radius_m).reshape(k, s)
        collided = ~np.all(free, axis=1, keepdims=False).astype(bool)
        last_free = np.where(collided, np.argmin(free, axis=1) - 1, s - 1)
        stays = last_free < 0  # the first sub-step already collides
        new_pose = np.where(stays[:, None], pose, track[np.arange(k), np.maximum(last_free, 0)])
        heading = new_pose[:, 2]
        velocity = speed[:, None] * np.column_stack([np.cos(heading), np.sin(heading)])
        velocity[collided] = 0.0
        return new_pose, velocity, collided

    def _sense(
        self, i: int, odometry: np.ndarray, velocity_xy: np.ndarray, rng: np.random.Generator
    ) -> None:
        """One frame of robot ``i``'s stack at its true pose, with the perturbations' hooks
        (``rng``: the localiser's draws)."""
        pert = self.perturbations[i]
        hooks: dict[str, Any] = {}
        if pert is not None:
            ctx, prng = self.frame_context(i), self.perturbation_rngs[i]
            hidden, extra = pert.radar_inputs(ctx, prng)
            hooks = {"hidden": hidden, "extra_scatterers": extra}
            hooks["filter_detections"] = lambda det: pert.filter_detections(ctx, det, prng)
        frame = self.stacks[i].step(
            self.pose[i].copy(),
            velocity_xy,
            odometry,
            rng,
            sensing_rng=self.sensing_rngs[i],
            **hooks,
        )
        self.frames[i] = frame
        self.estimates[i] = frame.estimate

    def frame_context(self, i: int) -> FrameContext:
        """What robot ``i``'s perturbations see of the current frame."""
        sensor = self.stacks[i].sensor
        return FrameContext(
            int(self.steps[i]),
            self.pose[i].copy(),
            self.world,
            sensor.world.layout,
            self.dt_s,
            sensor,
        )

    # ------------------------------------------------------------------ reading the state
    def path(self, i: int) -> WaypointPath:
        path = self.paths[i]
        if path is None:
            raise RuntimeError(f"robot {i} has no episode: reset it first")
        return path

    def estimate(self, i: int) -> PoseEstimate:
        est = self.estimates[i]
        if est is None:
            raise RuntimeError(f"robot {i} has no pose estimate: reset it first")
        return est

    def snapshot(self, i: int) -> NavSnapshot:
        """What robot ``i``'s observation is built from."""
        est = self.estimate(i)
        return NavSnapshot(
            est_pose=est.pose,
            est_std=est.std,
            converged=est.converged,
            confidence=est.confidence,
            n_modes=est.n_modes,
            true_pose=self.pose[i].copy(),
            path=self.path(i),
            s_est_m=float(self.s_est_m[i]),
            s_true_m=float(self.s_true_m[i]),
            last_action=self.last_action[i].copy(),
            room_size_m=self.world.room.size_m,
        )

    def observe(self, i: int) -> Any:
        """Robot ``i``'s observation (the single-robot space's element)."""
        return self.obs_type.observe(self.snapshot(i))

    def info(
        self, i: int, *, collided: bool, reached: bool, reward_terms: np.ndarray | None
    ) -> dict[str, Any]:
        """Robot ``i``'s info dict (see the env's docstring)."""
        est = self.estimate(i)
        pose = self.pose[i]
        frame = self.frames[i]
        detections = None if frame is None else frame.detections
        terms = np.zeros(len(REWARD_TERMS)) if reward_terms is None else reward_terms
        return {
            "true_pose": pose.copy(),
            "est_pose": est.pose.copy(),
            "position_error_m": float(np.hypot(*(est.pose[:2] - pose[:2]))),
            "heading_error_rad": float(np.abs(wrap_angle(est.pose[2] - pose[2]))),
            "pose_std": est.std,
            "n_particles": int(est.n_particles),
            "ess": float(est.ess),
            "n_detections": 0 if detections is None else len(detections),
            "converged": bool(est.converged),
            "localization_confidence": float(est.confidence),
            "n_modes": int(est.n_modes),
            "suspect_reflectors": () if frame is None else frame.suspect_reflectors,
            "progress_m": float(self.s_true_m[i]),
            "path_length_m": self.path(i).length_m,
            "collision": bool(collided),
            "is_success": bool(reached),
            "rewards": {name: float(v) for name, v in zip(REWARD_TERMS, terms, strict=True)},
        }


class RobotView:
    """One robot of a batch as the renderer and inspection tools read an env: its pose,
    path, estimate, stack stages and last frame (read-only)."""

    def __init__(self, batch: NavBatch, i: int) -> None:
        self.world = batch.world
        self.cfg = batch.cfg
        self._batch, self._i = batch, i

    @property
    def pose(self) -> np.ndarray:
        return self._batch.pose[self._i].copy()

    @property
    def path(self) -> WaypointPath | None:
        return self._batch.paths[self._i]

    @property
    def estimate(self) -> PoseEstimate | None:
        return self._batch.estimates[self._i]

    @property
    def stack(self) -> LocalizationStack:
        return self._batch.stacks[self._i]

    @property
    def localizer(self) -> Any:
        return self.stack.localizer

    @property
    def frame(self) -> FrameResult | None:
        return self._batch.frames[self._i]

    @property
    def detections(self) -> Any:
        return None if self.frame is None else self.frame.detections

    @property
    def fingerprint(self) -> Any:
        return None if self.frame is None else self.frame.fingerprint

    @property
    def _steps(self) -> int:
        return int(self._batch.steps[self._i])
