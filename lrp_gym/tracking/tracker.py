"""Track the distances to the reflectors over radar frames and report the fingerprint.

One Kalman filter per track (the equations in :mod:`lrp_gym.tracking.kalman`, for all tracks at
once), state
``(distance_m, rate_mps)``, measurement ``(range_m, velocity_mps)`` of a detection: the radar's
radial velocity *is* the rate of the distance. Without odometry the prediction is the paper's
linear motion model (next distance = distance + rate * dt); with it (:class:`EgoMotion`), each
track is predicted as a static point at its type's height (:mod:`lrp_gym.tracking.range_prediction`),
an extended-Kalman step that is exact while the robot drives straight.

Per frame (:meth:`LrpTracker.update`):

1. predict every track;
2. gate: a detection may feed a track when it passes the RCS/range window of the track's type
   (:class:`~lrp_gym.tracking.classify.LrpClassifier`), with odometry also the Doppler bound of
   a static point at that range, and the Mahalanobis gate of ``gate_probability``. Without
   odometry, persistent tracks gate the range (1 degree of freedom) and the rate only loosely
   (``rate_gate_mps``): when the robot turns, the radial velocities jump by up to twice the
   speed within one frame;
3. assign by global nearest neighbour (:func:`scipy.optimize.linear_sum_assignment`) on the
   2-D Mahalanobis distance plus an RCS-consistency term, persistent tracks first, then
   tentative ones on the detections left;
4. update the assigned filters; unassigned persistent tracks coast on their prediction (up to
   ``max_coast_frames`` misses in a row), tentative tracks must collect ``confirm_hits`` hits
   within ``confirm_window`` frames or are dropped;
5. start a tentative track on each window-passing detection left over that is not inside the
   range gate of an existing track of a type it may belong to (a second peak of it);
6. keep a bounded pool of persistent returns per type (reflectors, but also the ceiling, the
   wall-ceiling edges, multipath);
7. identify: per type, report the persistent tracks that best fill the type's reflector
   slots (one assignment problem): track quality and RCS fit, and with a
   :class:`~lrp_gym.tracking.prior.DistancePrior` the fit to each reflector's predicted
   distance (map-aided identification; tracks no prediction explains are never reported).

Output: per type, the reported tracks' filtered distances, variances and a ``fresh`` flag
(updated by a detection in this frame); never more than the type has reflectors. Free slots -
in the first frames or after losing a reflector - are filled with the best tentative tracks,
flagged not fresh, so positioning has distances from the very first frame; consumers that only
trust measured distances use :meth:`Fingerprint.fresh_only`.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.stats import chi2

from lrp_gym.config import TrackingConfig
from lrp_gym.radar.detections import Detections
from lrp_gym.tracking.classify import LrpClassifier, range_limits
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.tracking.identify import INFEASIBLE, POOL_FACTOR, ReflectorIdentifier
from lrp_gym.tracking.kalman import constant_velocity_model, kalman_predict, kalman_update
from lrp_gym.tracking.prior import DistancePrior
from lrp_gym.tracking.range_prediction import EgoMotion, ekf_predict_static, static_doppler_ok
from lrp_gym.tracking.track import Track, TrackView, tracks_fingerprint
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.world import World

_RCS_SMOOTHING = 0.3  # weight of a new RCS estimate in the track's running RCS
_NIS_SMOOTHING = 0.3  # weight of a new normalised innovation in the track's running mean


class LrpTracker:
    """Identify the reflectors among the detections and track their distances.

    Parameters
    ----------
    layout : ReflectorLayout
        Types, peak RCS and positions of the reflectors, and how many of each type there are.
    cfg : TrackingConfig
    max_range_m : float
        No reflector is farther than this (see :func:`~lrp_gym.tracking.classify.range_limits`).
    min_range_m : float
        No reflector is nearer than this.
    mount_height_m : float
        Height of the radar above the floor: with the reflector heights, it fixes how far
        below each reflector the radar passes, which the static-point prediction needs.
    """

    def __init__(
        self,
        layout: ReflectorLayout,
        cfg: TrackingConfig,
        *,
        max_range_m: float,
        min_range_m: float = 0.0,
        mount_height_m: float = 0.0,
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
        self.identifier = ReflectorIdentifier(
            cfg, self.classifier, tuple(int(c) for c in self._capacity), self.type_names
        )
        dz = np.abs(layout.positions_m[:, 2] - mount_height_m)
        # A type may be defined without any reflector (a catalogue): it never has a track, so
        # its heights are placeholders.
        sel = [layout.type_index == t for t in range(len(self.type_names))]
        self._height_m = np.array([dz[s].mean() if s.any() else 0.0 for s in sel])
        self._min_height_m = np.array([dz[s].min() if s.any() else 0.0 for s in sel])
        self._R = np.diag([cfg.measurement_std_m**2, cfg.velocity_std_mps**2])
        self._gate_range = float(chi2.ppf(cfg.gate_probability, 1))
        self._gate_2d = float(chi2.ppf(cfg.gate_probability, 2))
        self._window_mask = (1 << cfg.confirm_window) - 1
        self.reset()

    @classmethod
    def from_world(cls, world: World, cfg: TrackingConfig) -> LrpTracker:
        """A tracker whose range window follows from the room, layout and radar height."""
        lo, hi = range_limits(world.layout, world.room.size_m, world.mount_height_m)
        return cls(
            world.layout, cfg, max_range_m=hi, min_range_m=lo, mount_height_m=world.mount_height_m
        )

    # ------------------------------------------------------------------ public API
    def reset(self) -> None:
        """Forget every track (a new run)."""
        self._gated = (Detections(), np.zeros((0, len(self.type_names)), dtype=bool))
        self._tracks: list[Track] = []
        self._next_id = 0
        self._speed_mps: float | None = None  # ego speed at the previous frame

    @property
    def tracks(self) -> tuple[TrackView, ...]:
        """Snapshot of all current tracks (reported, candidate and tentative), by track id."""
        return tuple(
            TrackView(
                track_id=t.track_id,
                type_index=t.type_index,
                type_name=self.type_names[t.type_index],
                distance_m=float(t.x[0]),
                rate_mps=float(t.x[1]),
                variance_m2=float(t.P[0, 0]),
                rcs_dbsm=float(t.rcs_dbsm),
                status=t.status,
                age=t.age,
                misses=t.misses,
                fresh=t.fresh,
                nis=float(t.nis),
            )
            for t in self._tracks
        )

    def update(
        self,
        detections: Detections,
        dt_s: float,
        ego: EgoMotion | None = None,
        prior: DistancePrior | None = None,
        candidates: np.ndarray | None = None,
    ) -> Fingerprint:
        """Process one radar frame and return the estimated fingerprint.

        Parameters
        ----------
        detections : Detections
            This frame's detections (any number, including none).
        dt_s : float
            Time since the previous frame (> 0; ignored in the first frame).
        ego : EgoMotion, optional
            The robot's speed now and its odometry since the previous frame. With it, tracks
            are predicted as static points (:mod:`lrp_gym.tracking.range_prediction`), which is what
            separates the reflectors from room returns, and detections faster than a
            reflector at their range can be are not taken. Without it, the constant-velocity
            model of the paper.
        prior : DistancePrior, optional
            Predicted reflector distances from a pose estimate. With it, the reported tracks
            of a type are those that best match its reflectors' predictions (none is reported
            for a reflector that no track matches within the gate); without it, the
            best-scoring persistent tracks.
        candidates : ndarray of bool (N, T), optional
            ``classifier.candidates(detections)`` when the caller already has it (the window
            test of :meth:`gated_fingerprint` for the same frame); computed here otherwise.

        Returns
        -------
        Fingerprint
            Per type, sorted distances of the reported tracks (plus the best tentative ones
            filling free slots, flagged not fresh), their variances and fresh flags.
        """
        if not dt_s > 0:
            raise ValueError(f"dt_s must be positive, got {dt_s}")
        prev_speed = self._speed_mps
        static = ego is not None and prev_speed is not None
        if ego is not None and prev_speed is not None:
            self._predict_static(float(dt_s), ego, prev_speed)
        else:
            self._predict_cv(float(dt_s))
        for t in self._tracks:
            t.fresh = False
        self._speed_mps = None if ego is None else ego.speed_mps

        window = self.classifier.candidates(detections) if candidates is None else candidates
        self._gated = (detections, window)
        cand = (
            window
            if ego is None
            else window
            & static_doppler_ok(
                detections.range_m,
                detections.velocity_mps,
                self._min_height_m,
                ego.speed_mps,
                self.cfg.velocity_std_mps,
            )
        )
        z = np.column_stack([detections.range_m, detections.velocity_mps])
        free, explained = self._associate(detections, z, cand, static)
        for t in self._tracks:
            t.age += 1
            t.hits = ((t.hits << 1) | int(t.fresh)) & self._window_mask
            t.misses = 0 if t.fresh else t.misses + 1
        self._births(detections, z, cand, free, explained)
        ident = self.identifier
        self._tracks = ident.prune(
            self._tracks, POOL_FACTOR if prior is not None and prior.confident else 1
        )
        ident.select(self._tracks, prior)
        return ident.fingerprint(self._tracks, prior)

    def persistent_fingerprint(self, max_misses: int | None = None) -> Fingerprint:
        """Every persistent track (passed M of N), reported or not, per type.

        More distances than reflectors: the ones a positioning method cannot explain are the
        room's returns. Unlike the gated detections, one-frame clutter is not in it, so a fit
        statistic on it drops clearly when the pose hypothesis is wrong (kidnap detection).
        ``max_misses`` leaves out tracks that have coasted for more frames in a row: a
        coasting track follows the odometry, as a wrong pose hypothesis does.
        """
        by_type = [
            [
                t
                for t in self._tracks
                if t.type_index == ty
                and t.persistent
                and (max_misses is None or t.misses <= max_misses)
            ]
            for ty in range(len(self.type_names))
        ]
        return tracks_fingerprint(self.type_names, by_type, [[t.fresh for t in g] for g in by_type])

    def gated_fingerprint(
        self, detections: Detections | None = None, candidates: np.ndarray | None = None
    ) -> Fingerprint:
        """Detections that pass a type's RCS and range window, unsmoothed.

        Every reflector-like detection, not only the tracked ones: a positioning method with a
        clutter-aware likelihood (AMCL) uses them all; each goes to its best-fitting type.
        Without ``detections``: those of the last :meth:`update`. ``candidates`` is their
        window test (``classifier.candidates(detections)``) when the caller already has it.
        """
        if detections is None:
            detections, cand = self._gated  # the window test of the last update, reused
        else:
            cand = self.classifier.candidates(detections) if candidates is None else candidates
        best = self.classifier.classify(detections, cand)
        var = self.cfg.measurement_std_m**2
        order = np.argsort(detections.range_m, kind="stable")
        cls_sorted = best[order]
        idx = tuple(order[cls_sorted == t] for t in range(len(self.type_names)))
        dists = tuple(detections.range_m[i] for i in idx)
        return Fingerprint(
            self.type_names,
            dists,
            tuple(np.full(len(d), var) for d in dists),
            tuple(np.ones(len(d), dtype=bool) for d in dists),
            tuple(detections.velocity_mps[i] for i in idx),
        )

    # ------------------------------------------------------------------ prediction
    def _predict_cv(self, dt_s: float) -> None:
        if not self._tracks:
            return
        F, Q = constant_velocity_model(dt_s, self.cfg.process_accel_std_mps2)
        x, P = kalman_predict(*self._stacked(self._tracks), F, Q)
        self._unstack(self._tracks, x, P)

    def _predict_static(self, dt_s: float, ego: EgoMotion, prev_speed_mps: float) -> None:
        """Extended-Kalman prediction of every track as a static point of its type's height."""
        if not self._tracks:
            return
        x, P = self._stacked(self._tracks)
        h = self._height_m[[t.type_index for t in self._tracks]]
        _, Q = constant_velocity_model(dt_s, self.cfg.ego_accel_std_mps2)
        x, P = ekf_predict_static(x, P, h, float(prev_speed_mps), ego, Q)
        self._unstack(self._tracks, x, P)

    @staticmethod
    def _stacked(tracks: list[Track]) -> tuple[np.ndarray, np.ndarray]:
        """The tracks' states (n, 2) and covariances (n, 2, 2)."""
        return np.array([t.x for t in tracks]), np.array([t.P for t in tracks])

    @staticmethod
    def _unstack(tracks: list[Track], x: np.ndarray, P: np.ndarray) -> None:
        for t, xi, Pi in zip(tracks, x, P, strict=True):
            t.x, t.P = xi, Pi

    # ------------------------------------------------------------------ association
    def _associate(
        self, detections: Detections, z: np.ndarray, cand: np.ndarray, static: bool
    ) -> tuple[np.ndarray, np.ndarray]:
        """Gate and assign this frame's detections; return the (free, explained) masks (D,)."""
        free = np.ones(len(detections), dtype=bool)
        if not (self._tracks and len(detections)):
            return free, np.zeros(len(detections), dtype=bool)
        cost, ok, in_range_gate, d2 = self._gate(detections, z, cand, strict_all=static)
        persistent = np.array([t.persistent for t in self._tracks])
        # Persistent returns choose first; tentative ones share what is left.
        for rows in (np.flatnonzero(persistent), np.flatnonzero(~persistent)):
            if len(rows) and free.any():
                self._assign(rows, cost, ok & free[None, :], d2, detections, z, free)
        return free, np.asarray(in_range_gate.any(axis=0))

    def _gate(
        self, detections: Detections, z: np.ndarray, cand: np.ndarray, *, strict_all: bool
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Assignment cost, gate, range-gate and Mahalanobis matrices (tracks x detections).

        Tentative tracks gate on the 2-D Mahalanobis distance (2 degrees of freedom), so that
        clutter with random ranges and velocities rarely confirms; so do all tracks when they
        are predicted as static points (``strict_all``). With the constant-velocity model,
        persistent tracks gate on the range (1 degree of freedom) and a loose rate gate: when
        the robot turns, the radial velocities jump by up to twice the speed within one frame.
        The cost is the 2-D Mahalanobis distance plus the squared RCS change from the track's
        running RCS in units of half the RCS tolerance.
        """
        tracks = self._tracks
        x, P = self._stacked(tracks)  # predicted states
        S = P + self._R  # (n, 2, 2) innovation covariance
        types = np.array([t.type_index for t in tracks])
        strict = np.array([strict_all or not t.persistent for t in tracks])[:, None]
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
        return cost, ok, in_range_gate, d2

    def _assign(
        self,
        rows: np.ndarray,
        cost: np.ndarray,
        ok: np.ndarray,
        d2: np.ndarray,
        detections: Detections,
        z: np.ndarray,
        free: np.ndarray,
    ) -> None:
        """Global-nearest-neighbour assignment of free detections to tracks ``rows``."""
        sub_ok = ok[rows]
        if not sub_ok.any():
            return
        r_idx, c_idx = linear_sum_assignment(np.where(sub_ok, cost[rows], INFEASIBLE))
        keep = sub_ok[r_idx, c_idx]
        r_idx, c_idx = r_idx[keep], c_idx[keep]
        tracks = [self._tracks[rows[r]] for r in r_idx]
        x, P = kalman_update(*self._stacked(tracks), z[c_idx], self._R)
        self._unstack(tracks, x, P)
        for t, r, c in zip(tracks, rows[r_idx], c_idx, strict=True):
            t.rcs_dbsm += _RCS_SMOOTHING * (detections.rcs_dbsm[c] - t.rcs_dbsm)
            t.nis += _NIS_SMOOTHING * (min(d2[r, c], self._gate_2d) - t.nis)
            t.fresh = True
        free[c_idx] = False

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
            rcs = float(detections.rcs_dbsm[d])
            self._tracks.append(Track(self._next_id, int(ty), z[d].copy(), self._R.copy(), rcs))
            self._next_id += 1
