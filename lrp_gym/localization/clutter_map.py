"""Unmapped static scatterers, learnt while localised: a small clutter map.

A metal cabinet, a pipe or a corner the room model lacks returns a reflector-like echo from a
fixed place. The tracker follows it like any static point and nothing in the map explains it,
so every frame it competes with the reflectors: augmented MCL's fit on the persistent tracks
drops (it reads the unexplained track as a kidnap and injects random particles), and a wrong
pose where the scatterer happens to sit at a reflector's distance can win the injected
particles over. This is the landmark management of SLAM systems, kept small:

- **learn**: on frames where the localiser vouches for its estimate, a fresh persistent track
  whose distance no mapped reflector and no room return (structure, ghosts) explains adds one
  observation (the radar's estimated position, the track's distance). Once a track has
  ``min_observations`` of them, from positions that do not lie on one line, its point is
  fitted by least squares (:func:`fit_point`) and kept when the distances agree with it;
- **use**: the distances within ``gate_m`` of a clutter point's predicted distance, and of no
  mapped reflector's, are taken out of what the localiser weighs and out of the recovery fit
  (:meth:`ClutterMap.without_clutter`); the reflector monitor does not judge a reflector
  whose return a clutter point's would merge with;
- **forget**: a point with no return near its predicted distance for ``forget_frames``
  localised frames (moved furniture, a person who stood still) is dropped.

Only the distance is modelled, not the height above or below the radar: from a radar moving
in a plane, a point and its mirror image in that plane give the same distances.
"""

from __future__ import annotations

import itertools
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from lrp_gym.config.localization import ClutterMapConfig
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.world import World

#: Localised frames between two searches for a new point.
_SEARCH_EVERY = 8
#: A known point takes the nearest distance within this many ``gate_m`` as a new observation,
_REFINE_GATE = 1.5
#: keeps this many (the newest) and is refitted after every this many.
_MAX_POINT_OBSERVATIONS = 80
_REFIT_EVERY = 16
#: Gauss-Newton refinements after the linear start.
_REFINE_STEPS = 8
#: ... and when refining a known point.
_REFIT_STEPS = 3
#: A point whose distances are within this of a predicted room return ...
_ROOM_RETURN_TOL_M = 0.05
#: ... in this share of its frames is that room return; by chance, with ~8 room returns per
#: metre of range, about half the frames would match.
_ROOM_RETURN_SHARE = 0.8

#: Positions (N, 2) -> predicted room-return distances (K, N), or None without any.
MapRanges = Callable[[np.ndarray], "np.ndarray | None"]


def fit_point(
    radar_xy: np.ndarray, ranges_m: np.ndarray, start: np.ndarray | None = None
) -> tuple[np.ndarray, float]:
    """The static point that best explains distances measured from radar positions in a plane.

    Parameters
    ----------
    radar_xy : ndarray (K, 2)
        Radar positions over the floor (all at the same height), m.
    ranges_m : ndarray (K,)
        Distances measured from them, m.
    start : ndarray (3,), optional
        A point to refine (a refit); else the linear solution below.

    Returns
    -------
    point : ndarray (3,)
        ``(x_m, y_m, h_m)``: floor position and height above (or below) the radar plane.
    rms_m : float
        RMS of the distance residuals.

    Notes
    -----
    ``r^2 - |p|^2 = -2 p.q + (|q|^2 + h^2)`` is linear in ``(q, c = |q|^2 + h^2)``: a linear
    least-squares start, then Gauss-Newton on the distances themselves.
    """
    p = np.asarray(radar_xy, dtype=float)
    r = np.asarray(ranges_m, dtype=float)
    if start is None:
        a = np.column_stack([-2.0 * p, np.ones(len(p))])
        sol, *_ = np.linalg.lstsq(a, r**2 - np.sum(p**2, axis=1), rcond=None)
        q = sol[:2]
        x = np.array([*q, float(np.sqrt(max(sol[2] - q @ q, 1e-4)))])
    else:
        x = np.asarray(start, dtype=float).copy()
    for _ in range(_REFINE_STEPS if start is None else _REFIT_STEPS):
        d = np.column_stack([x[0] - p[:, 0], x[1] - p[:, 1], np.full(len(p), x[2])])
        pred = np.maximum(np.linalg.norm(d, axis=1), 1e-9)
        jac = d / pred[:, None]
        try:
            step = np.linalg.solve(jac.T @ jac, jac.T @ (r - pred))
        except np.linalg.LinAlgError:  # degenerate geometry: keep the last point
            break
        x = x + step
        x[2] = abs(x[2])
        if np.max(np.abs(step)) < 1e-6:
            break
    pred = np.sqrt((x[0] - p[:, 0]) ** 2 + (x[1] - p[:, 1]) ** 2 + x[2] ** 2)
    return x, float(np.sqrt(np.mean((r - pred) ** 2)))


def cross_spread_m(radar_xy: np.ndarray) -> float:
    """Std of the positions across their main direction (0 for positions on one line)."""
    p = np.asarray(radar_xy, dtype=float)
    if len(p) < 3:
        return 0.0
    return float(np.sqrt(max(np.linalg.eigvalsh(np.cov(p.T))[0], 0.0)))


def point_hypotheses(
    radar_xy: np.ndarray, ranges_m: list[np.ndarray], min_spread_m: float, anchors: int = 5
) -> np.ndarray:
    """Candidate static points (H, 3) from triples of buffered frames.

    ``anchors`` frames spread evenly over the buffer; every triple of them whose positions
    span a triangle (not a line: ``min_spread_m``) and every choice of one distance per frame
    of the triple is solved exactly (three equations of :func:`fit_point`'s linear form).
    A point missed in some frames is still found from the triples that saw it. Without
    randomness, so a seed still fixes the run.
    """
    p = np.asarray(radar_xy, dtype=float)
    picks = np.unique(np.linspace(0, len(p) - 1, anchors).round().astype(int))
    out = []
    for i, j, k in itertools.combinations(picks, 3):
        zs = [ranges_m[i], ranges_m[j], ranges_m[k]]
        q = p[[i, j, k]]
        # Twice the triangle's area over its longest side: the height of the triangle.
        u, v = q[1] - q[0], q[2] - q[0]
        area2 = abs(u[0] * v[1] - u[1] * v[0])
        side = max(np.linalg.norm(q[1] - q[0]), np.linalg.norm(q[2] - q[0]), 1e-9)
        if any(len(z) == 0 for z in zs) or area2 / side < min_spread_m:
            continue
        r = np.stack(np.meshgrid(*zs, indexing="ij"), axis=-1).reshape(-1, 3)
        a_mat = np.column_stack([-2.0 * q, np.ones(3)])
        sol = np.linalg.solve(a_mat, (r**2 - np.sum(q**2, axis=1)).T).T  # qx, qy, c
        h2 = sol[:, 2] - np.sum(sol[:, :2] ** 2, axis=1)
        ok = h2 > -0.05  # a small negative h^2 is noise on a point in the radar's plane
        out.append(np.column_stack([sol[ok, :2], np.sqrt(np.maximum(h2[ok], 0.0))]))
    return np.concatenate(out) if out else np.zeros((0, 3))


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
        # The last localised frames: radar position (2,) and the unexplained distances.
        self._frames: deque[tuple[np.ndarray, np.ndarray]] = deque(maxlen=self.cfg.window_frames)
        self._since_search = 0

    def add(self, point: np.ndarray, observations: np.ndarray | None = None) -> None:
        """Add a point ``(x_m, y_m, h_m)`` (and the ``(x, y, distance)`` rows it was fitted
        to, which later refits build on)."""
        self.points = np.vstack([self.points, np.asarray(point, dtype=float)[None, :3]])
        self._unseen = np.append(self._unseen, 0)
        rows = [] if observations is None else [tuple(map(float, o)) for o in observations]
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
        cand = cand[_inside(cand, size)]
        if not len(cand):
            return
        # Per hypothesis and frame, the distance nearest the predicted one.
        pred = np.sqrt(
            np.sum((pos[None, :, :] - cand[:, None, :2]) ** 2, axis=-1) + cand[:, 2:3] ** 2
        )
        nearest = _nearest(pred, [f[1] for f in frames])
        hits = np.abs(nearest - pred) <= cfg.gate_m
        best = int(np.argmax(hits.sum(axis=1)))
        inl = np.flatnonzero(hits[best])
        if len(inl) < cfg.min_observations or cross_spread_m(pos[inl]) < cfg.min_spread_m:
            return
        r = nearest[best, inl]
        point, rms = fit_point(pos[inl], r)
        if rms > cfg.max_rms_m or not _inside(point[None], size)[0]:
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
                self._refit(j, np.array(obs))

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
        if rms < float(np.sqrt(np.mean(res[ok] ** 2))) and _inside(point[None], self._size_m)[0]:
            self.points[j] = point


def _inside(points: np.ndarray, size_m: np.ndarray, margin_m: float = 0.1) -> np.ndarray:
    """Which points (P, 3) lie over the room's floor (within ``margin_m``) and no higher off
    the radar's plane than the room is tall."""
    return (
        np.all(points[:, :2] >= -margin_m, axis=1)
        & np.all(points[:, :2] <= size_m[:2] + margin_m, axis=1)
        & (points[:, 2] <= size_m[2])
    )


def _nearest(pred: np.ndarray, ranges_m: list[np.ndarray]) -> np.ndarray:
    """Per hypothesis and frame (H, K), the frame's distance nearest ``pred`` (inf without
    any): one sorted search over all frames, each frame's distances shifted apart."""
    h, k = pred.shape
    span = (
        2.0
        * max(float(np.max(pred, initial=0.0)), *(float(np.max(z, initial=0.0)) for z in ranges_m))
        + 1.0
    )
    z = np.concatenate([np.sort(zk) + i * span for i, zk in enumerate(ranges_m)] + [np.zeros(0)])
    if not len(z):
        return np.full(pred.shape, np.inf)
    q = pred + np.arange(k)[None, :] * span
    idx = np.searchsorted(z, q)
    lo = z[np.clip(idx - 1, 0, len(z) - 1)]
    hi = z[np.clip(idx, 0, len(z) - 1)]
    out = np.where(np.abs(lo - q) <= np.abs(hi - q), lo, hi) - np.arange(k)[None, :] * span
    # A neighbour from another frame is more than ``span`` / 2 away: no distance in this one.
    return np.where(np.abs(out - pred) < span / 2.0, out, np.inf)


def _is_room_return(radar_xy: np.ndarray, ranges_m: np.ndarray, map_ranges: MapRanges) -> bool:
    """Whether the distances ``ranges_m`` measured from ``radar_xy`` (K, 2) are, in almost
    every frame, one of the room returns the model predicts there (a ghost or a corner: they
    are static image points too, and the model already explains them)."""
    predicted = map_ranges(radar_xy)
    if predicted is None or not len(predicted):
        return False
    gap = np.abs(np.asarray(predicted, dtype=float) - np.asarray(ranges_m)[None, :])
    return bool(np.mean(np.min(gap, axis=0) <= _ROOM_RETURN_TOL_M) >= _ROOM_RETURN_SHARE)
