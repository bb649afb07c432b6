"""Observation types, pluggable by name through a registry (``env.observation.type``).

Every type turns a :class:`NavSnapshot` into an observation. The default ``estimated`` type uses
only what the robot knows: the AMCL estimate, its uncertainty, confidence and mode count, the
task's waypoints and its own last action. ``oracle`` swaps in the true pose (an ablation), ``dict`` exposes the same
content as a Dict space.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from lrp_gym.config import ObservationConfig
from lrp_gym.envs.task import WaypointPath


@dataclass(frozen=True)
class NavSnapshot:
    """What an observation may be built from after a step."""

    est_pose: np.ndarray  # (3,) estimated (x, y, theta)
    est_std: np.ndarray  # (3,) standard deviations of the estimate
    converged: bool
    confidence: float  # localiser's probability in [0, 1] that the estimate is right
    n_modes: int  # posterior modes with >= 5 % of the mass (0: none does, or unknown)
    true_pose: np.ndarray  # (3,) ground truth, used only by the oracle type
    path: WaypointPath
    s_est_m: float  # progress of the estimate along the path
    s_true_m: float  # progress of the true pose along the path
    last_action: np.ndarray  # (2,) in [-1, 1]
    room_size_m: np.ndarray  # (3,)


def unimodality(n_modes: int) -> float:
    """The mode count as a feature in [0, 1]: ``1 / n_modes``, and 0 when no mode is known.

    Why ``1 / n``: it is bounded whatever the localiser reports, equals 1 exactly when the
    posterior is in one mode, and falls monotonically as the mass splits (1/2 for a mirror
    pair). ``n_modes = 0`` means no cluster holds 5 % of the mass (a diffuse posterior, i.e.
    lost) or a localiser that does not count modes, so it maps to the "least unimodal" end.
    """
    return 1.0 / n_modes if n_modes > 0 else 0.0


def to_robot_frame(points_xy: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """World points (K, 2) expressed in the frame of ``pose`` (x forward, y left)."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    d = points_xy - pose[:2]
    return np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=-1)


OBSERVATION_TYPES: dict[str, type[ObservationType]] = {}


def register_observation(name: str):
    """Class decorator adding an observation type to the registry under ``name``."""

    def wrap(cls):
        cls.name = name
        OBSERVATION_TYPES[name] = cls
        return cls

    return wrap


def make_observation(cfg: ObservationConfig, room_size_m: np.ndarray) -> ObservationType:
    try:
        cls = OBSERVATION_TYPES[cfg.type]
    except KeyError:
        known = ", ".join(sorted(OBSERVATION_TYPES))
        raise ValueError(
            f"env.observation.type: unknown {cfg.type!r}; known types: {known}"
        ) from None
    return cls(cfg, room_size_m)


class ObservationType:
    """Base class: a space and a function from snapshot to observation."""

    name = "base"

    def __init__(self, cfg: ObservationConfig, room_size_m: np.ndarray) -> None:
        self.cfg = cfg
        self.room_size_m = np.asarray(room_size_m, dtype=float)
        self.reach_m = float(np.linalg.norm(self.room_size_m[:2]))

    @property
    def space(self) -> spaces.Space:
        raise NotImplementedError

    def observe(self, snap: NavSnapshot):
        raise NotImplementedError


class PoseObservation(ObservationType):
    """Shared content of the pose-based types: the pose (estimate or truth), its spread, the
    waypoints and goal in the robot frame, and the last action."""

    use_truth = False

    def _parts(self, snap: NavSnapshot):
        if self.use_truth:  # the truth is known exactly: certain, one mode
            pose, std, conv, s = snap.true_pose, np.zeros(3), True, snap.s_true_m
            conf, unimodal = 1.0, 1.0
        else:
            pose, std, conv, s = snap.est_pose, snap.est_std, snap.converged, snap.s_est_m
            conf = float(np.clip(snap.confidence, 0.0, 1.0))
            unimodal = unimodality(snap.n_modes)
        wps = to_robot_frame(snap.path.upcoming(s, self.cfg.n_waypoints), pose)
        goal = to_robot_frame(snap.path.goal_m[None, :], pose)[0]
        r = self.reach_m
        return (
            np.clip(pose[:2] / self.room_size_m[:2], -0.5, 1.5),
            np.array([np.cos(pose[2]), np.sin(pose[2])]),
            np.minimum(np.nan_to_num(std, nan=5.0), 5.0),
            float(conv),
            conf,
            unimodal,
            np.clip(wps, -r, r),
            np.clip(goal, -r, r),
            snap.last_action,
        )


@register_observation("estimated")
class EstimatedPoseObservation(PoseObservation):
    """Flat float32 vector built from the pose *estimate*.

    Layout (``n = n_waypoints``):

    ==========  =====  =================================================================
    index       count  content
    ==========  =====  =================================================================
    0-1         2      estimated x / Lx, y / Ly (0..1 inside the room)
    2-3         2      cos, sin of the estimated heading
    4-6         3      standard deviations of x, y (m) and heading (rad), capped at 5
    7           1      1.0 when localisation has converged, else 0.0
    8           1      localisation confidence in [0, 1] (``PoseEstimate.confidence``)
    9           1      unimodality 1 / n_modes in [0, 1] (0 when no mode holds 5 %)
    10..10+2n   2n     next n waypoints (dx, dy) in the estimated robot frame, metres
    10+2n..+2   2      goal (dx, dy) in the estimated robot frame, metres
    last 2      2      previous action
    ==========  =====  =================================================================
    """

    #: Length of the layout without the waypoints (10 pose/std/converged/confidence/modes +
    #: 2 goal + 2 action).
    FIXED_LEN = 14

    @staticmethod
    def fields(n_waypoints: int) -> dict[str, slice]:
        """Where each named part sits in the flat vector, for ``n_waypoints`` waypoints.

        Keys: ``position``, ``heading``, ``std``, ``converged``, ``confidence``, ``unimodality``,
        ``waypoints``, ``goal``, ``last_action`` (the table above); consumers read these instead of hard-coding indices.
        """
        n2 = 2 * n_waypoints
        return {
            "position": slice(0, 2),
            "heading": slice(2, 4),
            "std": slice(4, 7),
            "converged": slice(7, 8),
            "confidence": slice(8, 9),
            "unimodality": slice(9, 10),
            "waypoints": slice(10, 10 + n2),
            "goal": slice(10 + n2, 12 + n2),
            "last_action": slice(12 + n2, 14 + n2),
        }

    @classmethod
    def n_waypoints_of(cls, length: int) -> int:
        """Waypoint count of a flat observation of ``length`` values (ValueError if none fits)."""
        n, rest = divmod(length - cls.FIXED_LEN, 2)
        if n < 1 or rest:
            raise ValueError(f"observation: length {length} is not {cls.FIXED_LEN} + 2 n_waypoints")
        return n

    @property
    def space(self) -> spaces.Box:
        n = self.cfg.n_waypoints
        r = self.reach_m
        head_low = [-0.5, -0.5, -1, -1, 0, 0, 0, 0, 0, 0]
        head_high = [1.5, 1.5, 1, 1, 5, 5, 5, 1, 1, 1]
        low = np.array(head_low + [-r] * (2 * n + 2) + [-1, -1], np.float32)
        high = np.array(head_high + [r] * (2 * n + 2) + [1, 1], np.float32)
        return spaces.Box(low, high, dtype=np.float32)

    def observe(self, snap: NavSnapshot) -> np.ndarray:
        xy, cs, std, conv, conf, unimodal, wps, goal, act = self._parts(snap)
        head = [conv, conf, unimodal]
        return np.concatenate([xy, cs, std, head, wps.ravel(), goal, act]).astype(np.float32)


@register_observation("oracle")
class OraclePoseObservation(EstimatedPoseObservation):
    """Same layout as ``estimated`` but from the true pose (zero std, converged, confidence 1,
    one mode): an ablation baseline."""

    use_truth = True


@register_observation("dict")
class DictObservation(PoseObservation):
    """The ``estimated`` content as a Dict space with named parts."""

    @property
    def space(self) -> spaces.Dict:
        n, r = self.cfg.n_waypoints, self.reach_m
        f32 = np.float32
        return spaces.Dict(
            {
                "pose": spaces.Box(
                    np.array([-0.5, -0.5, -1, -1], f32), np.array([1.5, 1.5, 1, 1], f32)
                ),
                "pose_std": spaces.Box(0.0, 5.0, (3,), f32),
                "converged": spaces.Box(0.0, 1.0, (1,), f32),
                "confidence": spaces.Box(0.0, 1.0, (1,), f32),
                "unimodality": spaces.Box(0.0, 1.0, (1,), f32),
                "waypoints": spaces.Box(-r, r, (n, 2), f32),
                "goal": spaces.Box(-r, r, (2,), f32),
                "last_action": spaces.Box(-1.0, 1.0, (2,), f32),
            }
        )

    def observe(self, snap: NavSnapshot) -> dict[str, np.ndarray]:
        xy, cs, std, conv, conf, unimodal, wps, goal, act = self._parts(snap)
        f32 = np.float32
        return {
            "pose": np.concatenate([xy, cs]).astype(f32),
            "pose_std": std.astype(f32),
            "converged": np.array([conv], f32),
            "confidence": np.array([conf], f32),
            "unimodality": np.array([unimodal], f32),
            "waypoints": wps.astype(f32),
            "goal": goal.astype(f32),
            "last_action": np.asarray(act, f32),
        }
