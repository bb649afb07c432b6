"""Pure-pursuit path follower that reads only the env's observation vector.

The controller steers towards a *lookahead point*: the first point of the upcoming-waypoint
polyline (robot frame, from the observation) that lies ``lookahead`` metres from the robot. The
arc through that point has curvature ``2 y / L**2``; the turn rate is ``speed * curvature``.
Speed is the smallest of four limits: the robot's top speed, a lateral-acceleration limit on the
curvature (slow in sharp bends), an approach limit near the goal (do not overshoot the goal
tolerance within one frame), and an uncertainty limit (creep while the pose estimate is spread
out). While the heading is unknown the bearing to any target is meaningless, so the robot creeps
straight ahead: consistent motion is what lets the particle filter resolve the heading (a turn
on the spot shows the radar nothing new). Given the room (:meth:`PurePursuitPolicy.from_env`)
it creeps only where the floor ahead of the *estimated* pose is free for a few steps, and
turns on the spot where it is not (``avoid_walls_when_unsure``, on by default). When
the lookahead point lies far to the side or behind, the robot turns on the spot. At its
estimated goal in an episode that goes on (the env ends it when the true pose arrives), the
estimate is wrong: the robot creeps on, as while the heading is unknown, to show the filter
something new.

It is a :class:`~lrp_gym.experiments.episodes.Policy` (``reset``, ``act``) and also exposes the
Stable-Baselines3 ``predict`` signature.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from lrp_gym.envs.observations import EstimatedPoseObservation
from lrp_gym.world.room import Room

#: While the heading is unknown, a creep step is taken only where the floor ahead of the
#: estimated pose is free for this many steps (4 x 7.5 cm at the default creep speed).
CREEP_LOOKAHEAD_STEPS = 4

#: :meth:`PurePursuitPolicy.from_env` puts ``arrived_m`` at this share of the goal tolerance:
#: deep enough inside that an estimate a few cm off does not trigger it.
ARRIVED_SHARE = 0.5


@dataclass(frozen=True)
class PurePursuitConfig:
    """Controller gains and the robot limits the action is scaled by.

    Attributes
    ----------
    max_speed_mps, max_turn_rate_rps, max_reverse_mps : float
        Robot limits; the action is ``(speed / max_speed, turn / max_turn_rate)``, a reverse
        speed scaled by ``max_reverse_mps`` instead (as the env reads it).
    frame_period_s : float
        Time one action is held (the env's frame period).
    lookahead_m : float
        Lookahead distance at standstill.
    lookahead_time_s : float
        Extra lookahead per m/s of the previous speed (look further when fast).
    max_lateral_accel_mps2 : float
        Speed limit in bends: ``v <= sqrt(a / |curvature|)``.
    approach_gain : float
        Near the goal, travel at most this fraction of the remaining distance per frame.
    min_approach_speed_mps : float
        Floor of the approach limit so the robot does not stall just outside the tolerance.
    certain_std_m, uncertain_std_m : float
        Position std (largest of x, y) at and below which full speed is allowed, and at and
        above which the robot only creeps; linear in between.
    uncertain_heading_std_rad : float
        Heading std at and above which the robot only creeps.
    creep_speed_mps : float
        Speed while the estimate is uncertain (spread, heading or confidence).
    min_confidence : float
        The observation's localisation confidence below which the robot only creeps. 0.9, the
        localiser's ``settled_mass``, not the 0.99 at which it reports ``converged``: creeping
        until then timed out a fifth of the patrols under clutter (docs/trust.md, session 26).
    turn_in_place_rad : float
        Bearing of the lookahead point beyond which the robot turns on the spot.
    turn_gain : float
        Turn rate per radian of bearing when turning on the spot (1/s).
    avoid_walls_when_unsure : bool
        On by default (with a room): while the heading is unknown, creep only where the floor
        ahead of the estimated pose is free (``creep_margin_m``), and turn on the spot
        elsewhere. Off: creep blind. It removes most crashes of the patrols (kidnap put-downs
        facing a wall, clutter); sessions 18 and 26 kept it off because the turns, which
        weigh nothing, made the default task under clutter more often confidently wrong, which
        the localiser of session 28 no longer shows (docs/trust.md, session 28).
    creep_margin_m : float
        With ``avoid_walls_when_unsure``: the robot creeps only where its disc, widened by this
        margin, stays clear of walls and obstacles for :data:`CREEP_LOOKAHEAD_STEPS` creep steps
        ahead of the estimated pose, and turns on the spot elsewhere. Needs the room
        (:meth:`from_env`).
    arrived_m : float
        The env ends an episode when the *true* pose reaches the goal. An estimate within this
        distance of the goal, with only the goal left among the upcoming waypoints, in an
        episode that goes on is therefore wrong, by at least
        ``goal_tolerance - arrived_m``: the robot creeps on (as while the heading is unknown)
        to give the filter new evidence, instead of turning on the spot where it believes the
        goal is. 0 turns the rule off. :meth:`from_env` sets it to half the env's goal
        tolerance.
    """

    max_speed_mps: float = 2.0
    max_reverse_mps: float = 0.2
    max_turn_rate_rps: float = float(np.pi)
    frame_period_s: float = 0.25
    lookahead_m: float = 0.45
    lookahead_time_s: float = 0.2
    max_lateral_accel_mps2: float = 3.0
    approach_gain: float = 0.8
    min_approach_speed_mps: float = 0.3
    certain_std_m: float = 0.08
    uncertain_std_m: float = 0.3
    uncertain_heading_std_rad: float = 0.5
    creep_speed_mps: float = 0.3
    min_confidence: float = 0.9
    turn_in_place_rad: float = 1.2
    turn_gain: float = 3.0
    avoid_walls_when_unsure: bool = True
    creep_margin_m: float = 0.05
    arrived_m: float = 0.0


#: The settings a user may give (``lrp-gym evaluate --agent-option KEY=VALUE``): the robot
#: limits and the frame period come from the env.
USER_OPTIONS = tuple(
    f.name
    for f in fields(PurePursuitConfig)
    if f.name not in ("max_speed_mps", "max_reverse_mps", "max_turn_rate_rps", "frame_period_s")
)


def parse_options(items: Sequence[str]) -> dict[str, float | bool]:
    """``KEY=VALUE`` strings as typed :class:`PurePursuitConfig` settings.

    Raises
    ------
    ValueError
        Naming the item: no ``=``, a key that is not in :data:`USER_OPTIONS`, a value that is
        not a number (a bool: true/false/1/0/yes/no/on/off), or a number that is negative or
        not finite.
    """
    out: dict[str, float | bool] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key, text = key.strip(), text.strip()
        if not sep or not key:
            raise ValueError(f"expected KEY=VALUE, got {item!r}")
        if key not in USER_OPTIONS:
            raise ValueError(
                f"{item!r}: {key!r} is not a pure pursuit setting; choose from "
                + ", ".join(USER_OPTIONS)
            )
        if isinstance(getattr(PurePursuitConfig, key), bool):
            flags = {"true": True, "1": True, "yes": True, "on": True}
            flags |= {"false": False, "0": False, "no": False, "off": False}
            if text.lower() not in flags:
                raise ValueError(f"{item!r}: {key} takes true or false, got {text!r}")
            out[key] = flags[text.lower()]
            continue
        try:
            value = float(text)
        except ValueError:
            raise ValueError(f"{item!r}: {key} takes a number, got {text!r}") from None
        if not (np.isfinite(value) and value >= 0.0):
            raise ValueError(f"{item!r}: {key} must be a finite number >= 0, got {text!r}")
        out[key] = value
    return out


def lookahead_point(points: np.ndarray, distance_m: float) -> np.ndarray:
    """First point at ``distance_m`` from the origin along the polyline origin -> ``points``.

    Parameters
    ----------
    points : ndarray, shape (K, 2)
        Polyline vertices in the robot frame (the robot sits at the origin).
    distance_m : float
        Lookahead radius.

    Returns
    -------
    ndarray, shape (2,)
        Where the polyline first leaves the circle of radius ``distance_m``; the last vertex
        when the whole polyline lies inside the circle.
    """
    pts = np.vstack([np.zeros((1, 2)), np.asarray(points, dtype=float).reshape(-1, 2)])
    a, d = pts[:-1], np.diff(pts, axis=0)
    dd = np.einsum("ij,ij->i", d, d)
    ad = np.einsum("ij,ij->i", a, d)
    aa = np.einsum("ij,ij->i", a, a)
    disc = ad**2 - dd * (aa - distance_m**2)
    ok = (disc >= 0.0) & (dd > 1e-12)
    # Larger root of |a + t d| = L: where the segment leaves the circle.
    t = np.where(ok, (-ad + np.sqrt(np.where(ok, disc, 0.0))) / np.where(ok, dd, 1.0), -1.0)
    hit = ok & (t >= 0.0) & (t <= 1.0)
    if not hit.any():
        return pts[-1].copy()
    i = int(np.argmax(hit))
    return a[i] + t[i] * d[i]


class PurePursuitPolicy:
    """Pure pursuit on the observation vector of the ``estimated`` or ``oracle`` type.

    Parameters
    ----------
    config : PurePursuitConfig, optional
        Gains and robot limits; see :meth:`from_env` to take the limits from an env.
    room : Room, optional
        The room's geometry (walls, obstacles), for the clearance of a creep while the heading
        is unknown; None: creep blind, as far as the creep speed goes.
    robot_radius_m : float
        The robot's radius (m), with ``room``.
    """

    def __init__(
        self,
        config: PurePursuitConfig | None = None,
        room: Room | None = None,
        robot_radius_m: float = 0.0,
    ) -> None:
        self.config = config or PurePursuitConfig()
        self.room = room
        self.robot_radius_m = float(robot_radius_m)

    @classmethod
    def from_env(cls, env: Any, **gains: float) -> PurePursuitPolicy:
        """A policy whose robot limits, frame period and room match ``env`` (a gym env or
        wrapper)."""
        base = env.unwrapped
        lim = base.world.robot
        cfg = replace(
            PurePursuitConfig(),
            max_speed_mps=float(lim.max_speed_mps),
            max_turn_rate_rps=float(lim.max_turn_rate_rps),
            max_reverse_mps=float(lim.max_reverse_mps),
            frame_period_s=float(base.cfg.task.frame_period_s),
            **{"arrived_m": ARRIVED_SHARE * float(base.cfg.task.goal_tolerance_m), **gains},
        )
        return cls(cfg, base.world.room, float(lim.radius_m))

    def control(self, obs: np.ndarray) -> tuple[float, float]:
        """Speed (m/s) and turn rate (rad/s) for one flat observation."""
        c = self.config
        obs = np.asarray(obs, dtype=float)
        try:
            if obs.ndim != 1:
                raise ValueError
            n = EstimatedPoseObservation.n_waypoints_of(obs.shape[0])
        except ValueError:
            raise ValueError(
                f"pure pursuit needs the flat 'estimated'/'oracle' observation, got shape {obs.shape}"
            ) from None
        f = EstimatedPoseObservation.fields(n)
        std = obs[f["std"]]
        waypoints = obs[f["waypoints"]].reshape(n, 2)
        goal = obs[f["goal"]]
        last_speed = max(float(obs[f["last_action"]][0]), 0.0) * c.max_speed_mps

        lookahead = c.lookahead_m + c.lookahead_time_s * last_speed
        target = lookahead_point(np.vstack([waypoints, goal]), lookahead)
        dist = float(np.hypot(*target))
        bearing = float(np.arctan2(target[1], target[0]))
        goal_dist = float(np.hypot(*goal))

        # Speed limits: top speed, uncertainty, goal approach, bend.
        pos_std = float(np.max(std[:2]))
        frac = np.clip((c.uncertain_std_m - pos_std) / (c.uncertain_std_m - c.certain_std_m), 0, 1)
        on_last_leg = bool(np.all(np.abs(waypoints - goal) < 1e-6))  # only the goal ahead
        if goal_dist < c.arrived_m and on_last_leg:
            # "Arrived" but the episode goes on: the estimate is wrong. Frames at one spot are
            # weighed by the distance driven, so turning there would never correct it. (A
            # patrol passes its goal on every lap: there the waypoints go on.)
            return self._creep(obs[f["position"]], obs[f["heading"]])
        if std[2] >= c.uncertain_heading_std_rad:
            # Heading unknown: the bearing to the target is meaningless. Creep straight so the
            # filter sees consistent motion and can resolve the heading.
            if c.avoid_walls_when_unsure:
                return self._creep(obs[f["position"]], obs[f["heading"]])
            return c.creep_speed_mps, 0.0
        if obs[f["confidence"]][0] < c.min_confidence:
            frac = 0.0
        v = c.creep_speed_mps + frac * (c.max_speed_mps - c.creep_speed_mps)
        approach = max(c.approach_gain * goal_dist / c.frame_period_s, c.min_approach_speed_mps)
        v = min(v, approach)

        if abs(bearing) > c.turn_in_place_rad or dist < 1e-6:
            omega = float(np.clip(c.turn_gain * bearing, -c.max_turn_rate_rps, c.max_turn_rate_rps))
            return 0.0, omega
        curvature = 2.0 * target[1] / dist**2
        if abs(curvature) > 1e-9:
            v = min(v, np.sqrt(c.max_lateral_accel_mps2 / abs(curvature)))
            # Keep the arc when the turn rate saturates: slow down instead of cutting wider.
            v = min(v, c.max_turn_rate_rps / abs(curvature))
        return float(v), float(v * curvature)

    def _creep(self, position: np.ndarray, heading: np.ndarray) -> tuple[float, float]:
        """Straight creep while the heading is unknown where the floor ahead of the estimated
        pose (``position`` as a share of the room, ``heading`` as cos, sin) is free for
        :data:`CREEP_LOOKAHEAD_STEPS` steps; a turn on the spot where it is not."""
        c = self.config
        step_m = c.creep_speed_mps * c.frame_period_s
        if self.room is None or step_m <= 0.0:
            return c.creep_speed_mps, 0.0
        xy = np.asarray(position, float) * self.room.size_m[:2]
        norm = float(np.hypot(*heading))
        ahead = np.asarray(heading, float) / norm if norm > 0.0 else np.array([1.0, 0.0])
        # A cushion of several steps: the estimate may be a few cm off, and a creep that only
        # just fits zig-zags into a corner one short step after each turn.
        reach = np.linspace(0.0, CREEP_LOOKAHEAD_STEPS * step_m, 4 * CREEP_LOOKAHEAD_STEPS + 1)
        clearance = self.robot_radius_m + c.creep_margin_m
        if np.all(self.room.free(xy + reach[:, None] * ahead, clearance)):
            return c.creep_speed_mps, 0.0
        # Backing away instead (as much evidence as a step forward) was measured and crashed
        # as often as the blind creep: the heading that points ahead is unsure behind too.
        return 0.0, 0.5 * c.max_turn_rate_rps

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """Action(s) in ``[-1, 1]^2`` for one observation (D,) or a batch (N, D).

        Same signature and return as a Stable-Baselines3 policy; the controller is stateless.
        """
        obs = np.asarray(observation, dtype=float)
        batch = np.atleast_2d(obs)
        c = self.config
        out = np.empty((batch.shape[0], 2), dtype=np.float32)
        for i, row in enumerate(batch):
            v, w = self.control(row)
            scale = c.max_speed_mps if v >= 0.0 else max(c.max_reverse_mps, 1e-9)
            out[i] = (v / scale, w / c.max_turn_rate_rps)
        np.clip(out, -1.0, 1.0, out=out)
        return (out[0] if obs.ndim == 1 else out), state

    def reset(self) -> None:
        """The controller is stateless (the previous action comes in the observation)."""

    def act(self, observation: np.ndarray) -> np.ndarray:
        return self.predict(observation)[0]
