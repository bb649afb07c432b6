"""Track the distances to the reflectors over radar frames and report the fingerprint.

One constant-velocity Kalman filter (:class:`filterpy.kalman.KalmanFilter`) per track, state
``(distance_m, rate_mps)``, measurement ``(range_m, velocity_mps)`` of a detection: the radar's
radial velocity *is* the rate of the distance, so the linear motion model of the paper (next
distance = distance + rate * dt) is the filter's prediction and the measured velocity corrects
the rate directly.

Per frame (:meth:`LrpTracker.update`):

1. predict every track by ``dt_s``;
2. gate: a detection may feed a track when it passes the RCS/range window of the track's type
   (:class:`~lrp_gym.tracking.classify.LrpClassifier`), its range innovation passes the
   chi-square gate of ``gate_probability`` (1 degree of freedom) and its velocity innovation
   is below ``rate_gate_mps``. The velocity is gated loosely on purpose: when the robot turns,
   the radial velocities jump by up to twice the speed within one frame, and a strict 2-D gate
   would drop every reflector at every turn;
3. assign by global nearest neighbour (:func:`scipy.optimize.linear_sum_assignment`) on the
   2-D Mahalanobis distance plus an RCS-consistency term, confirmed tracks first, then
   tentative ones on the detections left;
4. update the assigned filters; unassigned confirmed tracks coast on their prediction (up to
   ``max_coast_frames`` misses in a row), tentative tracks must collect ``confirm_hits`` hits
   within ``confirm_window`` frames or are dropped;
5. start a tentative track on each window-passing detection left over that is not inside the
   gate of an existing track of the same type (a second peak of a tracked reflector);
6. keep at most as many confirmed tracks per type as the layout has reflectors of that type,
   and as many tentative ones, ranked by a score of hit rate, age, misses and RCS fit.

Output: per type, the confirmed tracks' filtered distances, variances and a ``fresh`` flag
(updated by a detection in this frame). While a type has fewer confirmed tracks than
reflectors - in the first frames or after losing one - its best tentative tracks fill the
free slots, flagged not fresh, so positioning has distances from the very first frame;
consumers that only trust measured distances use :meth:`Fingerprint.fresh_only`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from filterpy.common import Q_discrete_white_noise
from filterpy.kalman import KalmanFilter
from scipy.optimize import linear_sum_assignment
from scipy.stats import chi2

from lrp_gym.config import TrackingConfig
from lrp_gym.radar.detections import Detections
from lrp_gym.tracking.classify import LrpClassifier, range_limits
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.world import World

_INFEASIBLE = 1e9  # finite "forbidden" cost: linear_sum_assignment rejects all-inf rows
_RCS_SMOOTHING = 0.3  # weight of a new RCS estimate in the track's running RCS


@dataclass(frozen=True)
class TrackView:
    """Read-only snapshot of one track, for plotting and debugging.

    Attributes
    ----------
    track_id : int
        Unique within a tracker run (restarts at 0 after :meth:`LrpTracker.reset`).
    type_index : int
    type_name : str
    distance_m, rate_mps : float
        Filtered state after this frame.
    variance_m2 : float
        Variance of ``distance_m``.
    rcs_dbsm : float
        Running mean of the RCS estimates of the detections the track took.
    status : {"tentative", "confirmed"}
    age : int
        Frames since the track started (1 in its first frame).
    misses : int
        Consecutive frames without a detection.
    fresh : bool
        Updated by a detection in this frame.
    """

    track_id: int
    type_index: int
    type_name: str
    distance_m: float
    rate_mps: float
    variance_m2: float
    rcs_dbsm: float
    status: Literal["tentative", "confirmed"]
    age: int
    misses: int
    fresh: bool


class _Track:
    """Mutable track state around one filterpy Kalman filter."""

    __slots__ = (
        "track_id",
        "type_index",
        "kf",
        "rcs_dbsm",
        "hits",
        "age",
        "misses",
        "confirmed",
        "fresh",
    )

    def __init__(self, track_id: int, type_index: int, kf: KalmanFilter, rcs_dbsm: float) -> None:
        self.track_id = track_id
        self.type_index = type_index
        self.kf = kf
        self.rcs_dbsm = rcs_dbsm
        self.hits = 1  # bit i set: hit i frames ago
        self.age = 1
        self.misses = 0
        self.confirmed = False
        self.fresh = True


class LrpTracker:
    """Identify the reflectors among the detections and track their distances.

    Parameters
    ----------
    layout : ReflectorLayout
        Types and peak RCS of the reflectors, and how many of each type there are.
    cfg : TrackingConfig
    max_range_m : float
        No reflector is farther than this (see :func:`~lrp_gym.tracking.classify.range_limits`).
    min_range_m : float
        No reflector is nearer than this.
    """

    def __init__(
        self,
        layout: ReflectorLayout,
        cfg: TrackingConfig,
        *,
        max_range_m: float,
        min_range_m: float = 0.0,
    ) -> None:
        if not max_range_m > min_range_m >= 0.0:
            raise ValueError("need 0 <= min_range_m < max_range_m")
        self.layout = layout
        self.cfg = cfg
        self.type_names = layout.type_names
        self.classifier = LrpClassifier.from_layout(
            layout, cfg, max_range_m=max_range_m, min_range_m=min_range_m
        )
        self._capacity = layout.counts_per_type()
        self._R = np.diag([cfg.measurement_std_m**2, cfg.velocity_std_mps**2])
        self._gate_range = float(chi2.ppf(cfg.gate_probability, 1))
        self._gate_2d = float(chi2.ppf(cfg.gate_probability, 2))
        self._window_mask = (1 << cfg.confirm_window) - 1
        self._model_cache: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        self.reset()

    @classmethod
    def from_world(cls, world: World, cfg: TrackingConfig) -> LrpTracker:
        """A tracker whose range window follows from the room, layout and radar height."""
        lo, hi = range_limits(world.layout, world.room.size_m, world.mount_height_m)
        return cls(world.layout, cfg, max_range_m=hi, min_range_m=lo)

    # ------------------------------------------------------------------ public API
    def reset(self) -> None:
        """Forget every track (a new run)."""
        self._gated = (Detections(), np.zeros((0, len(self.type_names)), dtype=bool))
        self._tracks: list[_Track] = []
        self._next_id = 0

    @property
    def tracks(self) -> tuple[TrackView, ...]:
        """Snapshot of all current tracks (confirmed and tentative), by track id."""
        return tuple(
            TrackView(
                track_id=t.track_id,
                type_index=t.type_index,
                type_name=self.type_names[t.type_index],
                distance_m=float(t.kf.x[0, 0]),
                rate_mps=float(t.kf.x[1, 0]),
                variance_m2=float(t.kf.P[0, 0]),
                rcs_dbsm=float(t.rcs_dbsm),
                status="confirmed" if t.confirmed else "tentative",
                age=t.age,
                misses=t.misses,
                fresh=t.fresh,
            )
            for t in self._tracks
        )

    def update(self, detections: Detections, dt_s: float) -> Fingerprint:
        """Process one radar frame and return the estimated fingerprint.

        Parameters
        ----------
        detections : Detections
            This frame's detections (any number, including none).
        dt_s : float
            Time since the previous frame (> 0; ignored in the first frame).

        Returns
        -------
        Fingerprint
            Per type, sorted distances of the confirmed tracks (plus tentative ones filling
            free slots, flagged not fresh), their variances and fresh flags.
        """
        if not dt_s > 0:
            raise ValueError(f"dt_s must be positive, got {dt_s}")
        F, Q = self._model(float(dt_s))
        for t in self._tracks:
            t.kf.predict(F=F, Q=Q)
            t.fresh = False

        cand = self.classifier.candidates(detections)
        self._gated = (detections, cand)
        z = np.column_stack([detections.range_m, detections.velocity_mps])
        free = np.ones(len(detections), dtype=bool)
        explained = np.zeros(len(detections), dtype=bool)
        if self._tracks and len(detections):
            cost, ok, in_range_gate = self._gate(detections, z, cand)
            explained = in_range_gate.any(axis=0)
            confirmed = np.array([t.confirmed for t in self._tracks])
            # Confirmed tracks choose first; tentative ones share what is left.
            for rows in (np.flatnonzero(confirmed), np.flatnonzero(~confirmed)):
                if len(rows) and free.any():
                    self._assign(rows, cost, ok & free[None, :], detections, z, free)
        for t in self._tracks:
            t.age += 1
            t.hits = ((t.hits << 1) | int(t.fresh)) & self._window_mask
            t.misses = 0 if t.fresh else t.misses + 1
        self._births(detections, z, cand, free, explained)
        self._confirm_and_prune()
        return self._fingerprint()

    # ------------------------------------------------------------------ steps
    def gated_fingerprint(self) -> Fingerprint:
        """This frame's detections that pass a type's RCS and range window, unsmoothed.

        Every reflector-like detection, not only the tracked ones: a positioning method with a
        clutter-aware likelihood (AMCL) uses them all; each goes to its best-fitting type.
        """
        detections, cand = self._gated
        # The frame's window test is reused: this runs on every env step.
        best = self.classifier.classify(detections, cand)
        var = self.cfg.measurement_std_m**2
        dists = tuple(np.sort(detections.range_m[best == t]) for t in range(len(self.type_names)))
        return Fingerprint(
            self.type_names,
            dists,
            tuple(np.full(len(d), var) for d in dists),
            tuple(np.ones(len(d), dtype=bool) for d in dists),
        )

    def _model(self, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Transition and process noise of the constant-velocity model (cached per dt)."""
        model = self._model_cache.get(dt_s)
        if model is None:
            F = np.array([[1.0, dt_s], [0.0, 1.0]])
            Q = Q_discrete_white_noise(2, dt=dt_s, var=self.cfg.process_accel_std_mps2**2)
            model = (F, Q)
            if len(self._model_cache) < 64:
                self._model_cache[dt_s] = model
        return model

    def _gate(
        self, detections: Detections, z: np.ndarray, cand: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Assignment cost, gate and range-gate matrices (tracks x detections).

        Confirmed tracks gate on the range (1 degree of freedom) and the loose rate gate;
        tentative tracks on the 2-D Mahalanobis distance (2 degrees of freedom), so that
        clutter with random ranges and velocities rarely confirms. The cost is the 2-D
        Mahalanobis distance plus the squared RCS change from the track's running RCS in
        units of half the RCS tolerance.
        """
        tracks = self._tracks
        x = np.array([t.kf.x[:, 0] for t in tracks])  # (n, 2) predicted state
        S = np.array([t.kf.P for t in tracks]) + self._R  # (n, 2, 2) innovation covariance
        types = np.array([t.type_index for t in tracks])
        strict = np.array([not t.confirmed for t in tracks])[:, None]
        rcs = np.array([t.rcs_dbsm for t in tracks])[:, None]
        yr = z[None, :, 0] - x[:, 0, None]
        yv = z[None, :, 1] - x[:, 1, None]
        s00, s01, s11 = S[:, 0, 0, None], S[:, 0, 1, None], S[:, 1, 1, None]
        d2 = (s11 * yr * yr - 2.0 * s01 * yr * yv + s00 * yv * yv) / (s00 * s11 - s01 * s01)
        type_ok = cand[:, types].T
        in_range_gate = type_ok & (yr * yr <= self._gate_range * s00)
        loose = in_range_gate & (np.abs(yv) <= self.cfg.rate_gate_mps)
        ok = np.where(strict, type_ok & (d2 <= self._gate_2d), loose)
        cost = d2 + ((detections.rcs_dbsm[None, :] - rcs) / (0.5 * self.cfg.rcs_tolerance_db)) ** 2
        return cost, ok, in_range_gate

    def _assign(
        self,
        rows: np.ndarray,
        cost: np.ndarray,
        ok: np.ndarray,
        detections: Detections,
        z: np.ndarray,
        free: np.ndarray,
    ) -> None:
        """Global-nearest-neighbour assignment of free detections to tracks ``rows``."""
        sub_ok = ok[rows]
        if not sub_ok.any():
            return
        r_idx, c_idx = linear_sum_assignment(np.where(sub_ok, cost[rows], _INFEASIBLE))
        keep = sub_ok[r_idx, c_idx]
        r_idx, c_idx = r_idx[keep], c_idx[keep]
        tracks = [self._tracks[rows[r]] for r in r_idx]
        self._batch_update(tracks, z[c_idx])
        for t, c in zip(tracks, c_idx, strict=True):
            t.rcs_dbsm += _RCS_SMOOTHING * (detections.rcs_dbsm[c] - t.rcs_dbsm)
            t.fresh = True
        free[c_idx] = False

    def _batch_update(self, tracks: list[_Track], z: np.ndarray) -> None:
        """Kalman update of several tracks at once (H = I, Joseph form, as filterpy's update).

        One vectorised pass over the assigned tracks costs about as much as a single
        :meth:`KalmanFilter.update` call; the filters keep holding the state.
        """
        if not tracks:
            return
        x = np.array([t.kf.x[:, 0] for t in tracks])  # (m, 2)
        P = np.array([t.kf.P for t in tracks])  # (m, 2, 2)
        K = P @ np.linalg.inv(P + self._R)
        x = x + np.einsum("mij,mj->mi", K, z - x)
        I_K = np.eye(2) - K
        P = I_K @ P @ I_K.transpose(0, 2, 1) + K @ self._R @ K.transpose(0, 2, 1)
        for i, t in enumerate(tracks):
            t.kf.x = x[i].reshape(2, 1)
            t.kf.P = P[i]

    def _births(
        self,
        detections: Detections,
        z: np.ndarray,
        cand: np.ndarray,
        free: np.ndarray,
        explained: np.ndarray,
    ) -> None:
        """Tentative tracks on free window-passing detections.

        Detections inside the range gate of a track of a type they may belong to
        (``explained``) start nothing: they are a second peak of a tracked reflector.
        """
        idx = np.flatnonzero(free & ~explained & cand.any(axis=1))
        if len(idx) == 0:
            return
        fit = np.where(cand[idx], self.classifier.misfit(detections.rcs_dbsm[idx]), np.inf)
        best_type = np.argmin(fit, axis=1)
        for d, ty in zip(idx, best_type, strict=True):
            kf = KalmanFilter(dim_x=2, dim_z=2)
            kf.x = z[d].reshape(2, 1).copy()
            kf.P = self._R.copy()
            kf.H = np.eye(2)
            kf.R = self._R
            self._tracks.append(_Track(self._next_id, int(ty), kf, float(detections.rcs_dbsm[d])))
            self._next_id += 1

    def _score(self, t: _Track) -> float:
        """Rank of a track within its type: hit rate, age, misses and RCS fit."""
        hit_rate = bin(t.hits).count("1") / self.cfg.confirm_window
        misfit = (
            abs(t.rcs_dbsm - self.classifier.centre_dbsm[t.type_index])
            / (self.classifier.half_width_db[t.type_index])
        )
        # Age weighs as much as the hit rate: an established track is not pushed out by a
        # newly confirmed one while it merely coasts through a few missed detections.
        return (
            hit_rate
            + min(t.age, 20) / 20.0
            - t.misses / (self.cfg.max_coast_frames + 1.0)
            - 0.5 * misfit
        )

    def _confirm_and_prune(self) -> None:
        cfg = self.cfg
        kept: list[_Track] = []
        for t in self._tracks:
            if not t.confirmed and bin(t.hits).count("1") >= cfg.confirm_hits:
                t.confirmed = True
            if t.confirmed and t.misses > cfg.max_coast_frames:
                continue
            if not t.confirmed and t.age >= cfg.confirm_window:
                continue  # could not collect its hits within the window
            kept.append(t)
        final: list[_Track] = []
        for ty, cap in enumerate(self._capacity):
            for confirmed in (True, False):
                same = [t for t in kept if t.type_index == ty and t.confirmed == confirmed]
                if len(same) > cap:
                    same = sorted(same, key=lambda t: (-self._score(t), t.track_id))[:cap]
                final.extend(same)
        final.sort(key=lambda t: t.track_id)
        self._tracks = final

    def _fingerprint(self) -> Fingerprint:
        dists, variances, fresh = [], [], []
        for ty, cap in enumerate(self._capacity):
            conf = [t for t in self._tracks if t.type_index == ty and t.confirmed]
            if len(conf) < cap:
                tent = sorted(
                    (t for t in self._tracks if t.type_index == ty and not t.confirmed),
                    key=lambda t: (-self._score(t), t.track_id),
                )
                chosen = conf + tent[: cap - len(conf)]
                flags = [t.fresh for t in conf] + [False] * (len(chosen) - len(conf))
            else:
                chosen, flags = conf, [t.fresh for t in conf]
            d = np.array([t.kf.x[0, 0] for t in chosen], dtype=float)
            v = np.array([t.kf.P[0, 0] for t in chosen], dtype=float)
            f = np.array(flags, dtype=bool)
            order = np.argsort(d, kind="stable")
            dists.append(d[order])
            variances.append(v[order])
            fresh.append(f[order])
        return Fingerprint(self.type_names, tuple(dists), tuple(variances), tuple(fresh))
