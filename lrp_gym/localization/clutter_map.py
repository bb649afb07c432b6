"""Unmapped static scatterers, learnt while localised: a small clutter map.

A metal cabinet, a pipe or a corner the room model lacks returns a reflector-like echo from a
fixed place. The tracker follows it like any static point and nothing in the map explains it,
so every frame it competes with the reflectors: augmented MCL's fit on the persistent tracks
drops (it reads the unexplained track as a kidnap and injects random particles), and a wrong
pose where the scatterer happens to sit at a reflector's distance can win the injected
particles over. This is the landmark management of SLAM systems, kept small:

- **learn**: on frames where the localiser vouches for its estimate, the reflector-like
  distances that no mapped reflector and no known point explains are buffered with the
  estimate's position. Every few frames, triples of buffered frames give exact candidate
  points (:func:`~lrp_gym.localization.point_fit.point_hypotheses`); the candidate with a
  distance in most frames, seen from positions that do not lie on one line, is fitted by
  least squares (:func:`~lrp_gym.localization.point_fit.fit_point`) and kept when the
  distances agree with it and the model's room returns (structure, ghosts) do not already
  predict them;
- **refine**: each point takes its nearest distance of later frames and is refitted now and
  then, from more of the path;
- **use**: the distances within ``gate_m`` of a clutter point's predicted distance, and of no
  mapped reflector's, are taken out of what the localiser weighs and out of the recovery fit
  (:meth:`ClutterMap.declutter`), predicted from the last converged estimate moved by the
  odometry; the reflector monitor does not judge a reflector whose return a clutter point's
  would merge with;
- **forget**: a point with no return near its predicted distance for ``forget_frames``
  localised frames (moved furniture, a person who stood still) is dropped.

Off by default (``localization.clutter_map.enabled``): on the simulated clutter it gained
nothing measurable (docs/robustness.md), because AMCL's clutter class already absorbs the
scatterers' returns.

Only the distance is modelled, not the height above or below the radar: from a radar moving
in a plane, a point and its mirror image in that plane give the same distances.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from lrp_gym.config.room_changes import ClutterMapConfig
from lrp_gym.localization.point_fit import (
    cross_spread_m,
    fit_point,
    inside_room,
    nearest_distances,
    point_hypotheses,
)
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.robot import apply_odometry
from lrp_gym.world.world import World

#: Localised frames between two searches for a new point.
_SEARCH_EVERY = 8
#: A known point takes the nearest distance within this many ``gate_m`` as a new observation,
_REFINE_GATE = 1.5
#: keeps this many (the newest) and is refitted after every this many.
_MAX_POINT_OBSERVATIONS = 80
_REFIT_EVERY = 16
#: A point whose distances are within this of a predicted room return ...
_ROOM_RETURN_TOL_M = 0.05
#: ... in this share of its frames is that room return; by chance, with ~8 room returns per
#: metre of range, about half the frames would match.
_ROOM_RETURN_SHARE = 0.8

#: Positions (N, 2) -> predicted room-return distances (K, N), or None without any.
MapRanges = Callable[[np.ndarray], "np.ndarray | None"]


@dataclass
class ClutterMap:
    """One robot's clutter points and the observations of its candidate tracks.

    Parameters
    ----------
    world : World
        The surveyed map (layout, room, radar height).
    cfg : ClutterMapConfig

    Attributes
    ----------
    points : ndarray (P, 3)
        Learnt points ``(x_m, y_m, h_m)`` (``h_m``: height off the radar plane).
    """

    world: World
    cfg: ClutterMapConfig
    points: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self._size_m = np.asarray(self.world.room.size_m, dtype=float)
        self.reset()

    def reset(self) -> None:
        """Forget every point and observation (a new run)."""
        self.points = np.zeros((0, 3))
        self._unseen = np.zeros(0, dtype=np.int64)  # localised frames without a return
        # Per point, the (x, y, distance) it was fitted to and has matched since.
        self._point_obs: list[list[tuple[float, float, float]]] = []
        self._matched = np.zeros(0, dtype=np.int64)  # per point, observations since its fit
        # The last converged estimate, moved by the odometry since, and the frames since.
        self._anchor_pose: np.ndarray | None = None
        self._unconverged_frames = 0
        # The last localised frames: radar position (2,) and the unexplained distances.
        self._frames: deque[tuple[np.ndarray, np.ndarray]] = deque(maxlen=self.cfg.window_frames)
        self._since_search = 0

    def follow(self, pose: np.ndarray, converged: bool, odometry: np.ndarray) -> None:
        """Keep the pose the points are predicted from: this frame's estimate when it has
        converged, else the last converged one moved by this frame's ``odometry``."""
        if converged:
            self._anchor_pose, self._unconverged_frames = np.asarray(pose, dtype=float), 0
        elif self._anchor_pose is not None:
            self._anchor_pose = apply_odometry(self._anchor_pose, odometry)
            self._unconverged_frames += 1

    def declutter(self, fingerprint: Fingerprint, odometry: np.ndarray) -> Fingerprint:
        """``fingerprint`` without the points' returns, predicted from the anchor pose moved by
        this frame's ``odometry`` (:meth:`without_clutter`).

        Also for ``dead_reckoning_frames`` frames after the estimate stopped being converged:
        that is when clutter does its harm (a cloud spread by recovery particles finds poses
        where the clutter sits at reflector distances), while the odometry still knows the
        pose well.
        """
        anchor = self._anchor_pose
        if not len(self.points) or anchor is None:
            return fingerprint
        if self._unconverged_frames > self.cfg.dead_reckoning_frames:
            return fingerprint
        return self.without_clutter(fingerprint, apply_odometry(anchor, odometry)[:2])

    def add(self, point: np.ndarray, observations: np.ndarray | None = None) -> None:
        """Add a point ``(x_m, y_m, h_m)`` (and the ``(x, y, distance)`` rows it was fitted
        to, which later refits build on)."""
        self.points = np.vstack([self.points, np.asarray(point, dtype=float)[None, :3]])
        self._unseen = np.append(self._unseen, 0)
        rows = (
            []
            if observations is None
            else [(float(a), float(b), float(c)) for a, b, c in observations]
        )
        self._point_obs.append(rows)
        self._matched = np.append(self._matched, 0)

    def predicted_m(self, xy: np.ndarray) -> np.ndarray:
        """Distances (P,) from the radar at floor position ``xy`` to the points."""
        d = self.points[:, :2] - np.asarray(xy, dtype=float)[:2]
        return np.sqrt(np.sum(d**2, axis=1) + self.points[:, 2] ** 2)

    def without_clutter(self, fingerprint: Fingerprint, xy: np.ndarray) -> Fingerprint:
        """``fingerprint`` without the distances a clutter point explains from ``xy``.

        A distance within ``gate_m`` of a point's predicted distance goes, unless it is also
        within ``gate_m`` of a mapped reflector's (then the two cannot be told apart, and the
        reflector keeps it).
        """
        if not len(self.points) or fingerprint.count == 0:
            return fingerprint
        clutter = self.predicted_m(xy)
        mapped = self.world.true_distances_m(np.asarray(xy, dtype=float)[:2])
        gate = self.cfg.gate_m
        keep = []
        for z in fingerprint.distances_m:
            near_clutter = np.any(np.abs(z[:, None] - clutter[None, :]) <= gate, axis=1)
            near_mapped = np.any(np.abs(z[:, None] - mapped[None, :]) <= gate, axis=1)
            keep.append(~near_clutter | near_mapped)
        if all(k.all() for k in keep):
            return fingerprint
        vel = fingerprint.velocities_mps
        return Fingerprint(
            fingerprint.type_names,
            tuple(z[k] for z, k in zip(fingerprint.distances_m, keep, strict=True)),
            tuple(v[k] for v, k in zip(fingerprint.variances_m2, keep, strict=True)),
            tuple(f[k] for f, k in zip(fingerprint.fresh, keep, strict=True)),
            None if vel is None else tuple(v[k] for v, k in zip(vel, keep, strict=True)),
        )

    def update(
        self, xy: np.ndarray, gated: Fingerprint, map_ranges: MapRanges | None = None
    ) -> None:
        """Learn from and refresh with one localised frame.

        Parameters
        ----------
        xy : ndarray (2,)
            The (converged) estimate's floor position.
        gated : Fingerprint
            This frame's reflector-like detections (every type).
        map_ranges : callable, optional
            Positions (N, 2) -> distances (K, N) of the room returns the measurement model
            predicts (structure, ghosts), or None; a point that is one of them is not clutter.
        """
        xy = np.asarray(xy, dtype=float)[:2]
        z = np.concatenate([np.zeros(0), *gated.distances_m])
        self._refresh(xy, z)
        # What a mapped reflector or a known point explains is no evidence of a new point.
        explained = np.concatenate([self.world.true_distances_m(xy), self.predicted_m(xy)])
        near = np.abs(z[:, None] - explained[None, :]) <= self.cfg.explain_gate_m
        self._frames.append((xy, z[~near.any(axis=1)]))
        self._since_search += 1
        if self._since_search >= _SEARCH_EVERY and len(self._frames) >= self.cfg.min_observations:
            self._since_search = 0
            self._search(map_ranges)

    def _search(self, map_ranges: MapRanges | None) -> None:
        """Look for one static point in the buffered frames (see :func:`point_hypotheses`)."""
        cfg = self.cfg
        if len(self.points) >= cfg.max_points:
            return
        frames = list(self._frames)
        pos = np.array([f[0] for f in frames])
        size = self._size_m
        cand = point_hypotheses(pos, [f[1] for f in frames], cfg.min_spread_m)
        cand = cand[inside_room(cand, size)]
        if not len(cand):
            return
        # Per hypothesis and frame, the distance nearest the predicted one.
        pred = np.sqrt(
            np.sum((pos[None, :, :] - cand[:, None, :2]) ** 2, axis=-1) + cand[:, 2:3] ** 2
        )
        nearest = nearest_distances(pred, [f[1] for f in frames])
        hits = np.abs(nearest - pred) <= cfg.gate_m
        best = int(np.argmax(hits.sum(axis=1)))
        inl = np.flatnonzero(hits[best])
        if len(inl) < cfg.min_observations or cross_spread_m(pos[inl]) < cfg.min_spread_m:
            return
        r = nearest[best, inl]
        point, rms = fit_point(pos[inl], r)
        if rms > cfg.max_rms_m or not inside_room(point[None], size)[0]:
            return
        # Its returns are used up either way: a room return is searched for only once.
        for k, rk in zip(inl, r, strict=True):
            xy_k, z_k = self._frames[k]
            self._frames[k] = (xy_k, z_k[z_k != rk])
        if map_ranges is not None and _is_room_return(pos[inl], r, map_ranges):
            return
        rows = np.column_stack([pos[inl], r])
        if len(self.points):
            # A known point whose prediction drifted past the explain gate: the same point.
            known = np.sqrt(
                np.sum((pos[inl][None, :, :] - self.points[:, None, :2]) ** 2, axis=-1)
                + self.points[:, 2:3] ** 2
            )
            same = np.mean(np.abs(known - r[None, :]) <= cfg.gate_m, axis=1)
            j = int(np.argmax(same))
            if same[j] >= 0.5:
                self._point_obs[j].extend(map(tuple, rows))
                del self._point_obs[j][:-_MAX_POINT_OBSERVATIONS]
                return
        self.add(point, rows)

    def _refresh(self, xy: np.ndarray, z: np.ndarray) -> None:
        """Count localised frames without a distance ``z`` near each point's; forget the
        points past ``forget_frames`` (only frames where the point is in the radar's range)."""
        if not len(self.points):
            return
        pred = self.predicted_m(xy)
        seen = (
            np.any(np.abs(z[None, :] - pred[:, None]) <= self.cfg.gate_m, axis=1)
            if len(z)
            else np.zeros(len(pred), dtype=bool)
        )
        in_range = pred <= self.world.fmcw.max_range_m
        self._unseen = np.where(seen, 0, self._unseen + in_range)
        if len(z):
            self._refine(xy, z, pred)
        keep = self._unseen <= self.cfg.forget_frames
        self.points, self._unseen = self.points[keep], self._unseen[keep]
        self._point_obs = [o for o, k in zip(self._point_obs, keep, strict=True) if k]
        self._matched = self._matched[keep]

    def _refine(self, xy: np.ndarray, z: np.ndarray, pred: np.ndarray) -> None:
        """Add this frame's nearest distance to each point's observations and refit now and
        then: a point fitted from one stretch of the path predicts its distance well there
        only (range-only geometry), and the robot goes on to see it from elsewhere."""
        gap = np.abs(z[None, :] - pred[:, None])
        nearest = np.argmin(gap, axis=1)
        for j in np.flatnonzero(
            gap[np.arange(len(pred)), nearest] <= _REFINE_GATE * self.cfg.gate_m
        ):
            obs = self._point_obs[j]
            obs.append((xy[0], xy[1], float(z[nearest[j]])))
            del obs[:-_MAX_POINT_OBSERVATIONS]
            self._matched[j] += 1
            if self._matched[j] % _REFIT_EVERY == 0:
                self._refit(int(j), np.array(obs))

    def _refit(self, j: int, obs: np.ndarray) -> None:
        """Refit point ``j`` to its observations (x, y, distance); kept when it explains the
        inliers (within ``gate_m`` of the current prediction: another return may have come
        near) better than the current point does."""
        xy, r = obs[:, :2], obs[:, 2]
        current = self.points[j]
        res = np.abs(np.sqrt(np.sum((xy - current[:2]) ** 2, axis=1) + current[2] ** 2) - r)
        ok = res <= self.cfg.gate_m
        if ok.sum() < self.cfg.min_observations:
            return
        point, rms = fit_point(xy[ok], r[ok], start=current)
        if (
            rms < float(np.sqrt(np.mean(res[ok] ** 2)))
            and inside_room(point[None], self._size_m)[0]
        ):
            self.points[j] = point


def _is_room_return(radar_xy: np.ndarray, ranges_m: np.ndarray, map_ranges: MapRanges) -> bool:
    """Whether the distances ``ranges_m`` measured from ``radar_xy`` (K, 2) are, in almost
    every frame, one of the room returns the model predicts there (a ghost or a corner: they
    are static image points too, and the model already explains them)."""
    predicted = map_ranges(radar_xy)
    if predicted is None or not len(predicted):
        return False
    gap = np.abs(np.asarray(predicted, dtype=float) - np.asarray(ranges_m)[None, :])
    return bool(np.mean(np.min(gap, axis=0) <= _ROOM_RETURN_TOL_M) >= _ROOM_RETURN_SHARE)
