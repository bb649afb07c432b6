"""Which persistent tracks are the reflectors: scores, the candidate pool and the report.

Per type, the reported tracks fill the type's reflector slots in one assignment problem:
the cost of a track in a slot is minus its score (hit rate, age, misses, RCS fit), with a
hysteresis bonus for tracks already reported, and - with a
:class:`~lrp_gym.tracking.prior.DistancePrior` - minus the log-likelihood ratio of its distance
under that reflector's predicted distance against clutter (map-aided identification).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.stats import chi2

from lrp_gym.config import TrackingConfig
from lrp_gym.tracking.classify import LrpClassifier
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.tracking.prior import DistancePrior
from lrp_gym.tracking.track import NIS_EXPECTED, Track, tracks_fingerprint

INFEASIBLE = 1e9  # finite "forbidden" cost: linear_sum_assignment rejects all-inf rows
POOL_FACTOR = 3  # persistent returns kept per type, in units of the type's reflector count
_SELECT_MARGIN = 0.3  # score lead a candidate needs to take over a reported track


class ReflectorIdentifier:
    """Scores tracks, bounds the pool of persistent returns and picks the reported ones.

    Parameters
    ----------
    cfg : TrackingConfig
    classifier : LrpClassifier
        RCS windows (for the RCS fit) and the range window (for the clutter density).
    capacity : tuple of int
        Reflectors per type.
    type_names : tuple of str
    """

    def __init__(
        self,
        cfg: TrackingConfig,
        classifier: LrpClassifier,
        capacity: tuple[int, ...],
        type_names: tuple[str, ...],
    ) -> None:
        self.cfg = cfg
        self.classifier = classifier
        self.capacity = capacity
        self.type_names = type_names
        self.gate_range = float(chi2.ppf(cfg.gate_probability, 1))
        # Clutter density in the range window is 1 / width: the prior's reference.
        self.log_window_m = float(np.log(classifier.max_range_m - classifier.min_range_m))

    def score(self, t: Track) -> float:
        """How much a track looks like one of its type's reflectors (higher: more).

        Hit rate, age, misses, RCS fit, and (weighted by ``nis_weight``, off by default) how
        well it follows the motion model: a room return that moves with the robot (ceiling, a
        wall's specular point) keeps a running normalised innovation above the 2 of a static
        reflector.
        """
        hit_rate = bin(t.hits).count("1") / self.cfg.confirm_window
        misfit = (
            abs(t.rcs_dbsm - self.classifier.centre_dbsm[t.type_index])
            / (self.classifier.half_width_db[t.type_index])
        )
        excess_nis = max(t.nis - NIS_EXPECTED, 0.0) / NIS_EXPECTED
        # Age weighs as much as the hit rate: an established track is not pushed out by a
        # newly persistent one while it merely coasts through a few missed detections.
        return (
            hit_rate
            + min(t.age, 20) / 20.0
            - t.misses / (self.cfg.max_coast_frames + 1.0)
            - 0.5 * misfit
            - self.cfg.nis_weight * excess_nis
        )

    def prune(self, tracks: list[Track], pool_factor: int) -> list[Track]:
        """M-of-N persistence, deletion, and a bounded pool of tracks per type.

        ``pool_factor`` times as many persistent returns as reflectors are kept: the tracker
        passes ``POOL_FACTOR`` with a confident prior to choose among them, else 1 (the
        paper's rule: more candidates would only add chances to report a room return).
        """
        cfg = self.cfg
        kept: list[Track] = []
        for t in tracks:
            if not t.persistent and bin(t.hits).count("1") >= cfg.confirm_hits:
                t.persistent = True
            if t.persistent and t.misses > cfg.max_coast_frames:
                continue
            if not t.persistent and t.age >= cfg.confirm_window:
                continue  # could not collect its hits within the window
            kept.append(t)
        final: list[Track] = []
        for ty, cap in enumerate(self.capacity):
            for persistent in (True, False):
                same = [t for t in kept if t.type_index == ty and t.persistent == persistent]
                if len(same) > pool_factor * cap:
                    same = sorted(same, key=lambda t: (-self.score(t), t.track_id))
                    same = same[: pool_factor * cap]
                final.extend(same)
        final.sort(key=lambda t: t.track_id)
        return final

    def _slot_costs(
        self, tracks: list[Track], ty: int, prior: DistancePrior | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Cost (tracks x reflector slots of type ``ty``) of reporting a track in a slot.

        Minus the track's score, minus ``_SELECT_MARGIN`` for a track already reported (so
        that near-equal scores do not flip the identity back and forth), and, with a prior,
        minus the log-likelihood ratio of the track's distance under the reflector's predicted
        distance against clutter spread evenly over the range window. A sharp prediction that
        fits earns a bonus, one that does not a penalty (beyond the 1-degree-of-freedom gate:
        forbidden), and a vague prior (a cloud spread over the room) changes little. A prior
        that is not ``confident`` only forbids.
        """
        cap = self.capacity[ty]
        base = np.array([-self.score(t) - _SELECT_MARGIN * t.selected for t in tracks])
        cost = np.repeat(base[:, None], cap, axis=1)
        feasible = np.ones(cost.shape, dtype=bool)
        if prior is not None:
            d = np.array([t.x[0] for t in tracks])
            var = np.array([t.P[0, 0] for t in tracks]) + self.cfg.measurement_std_m**2
            llr = prior.log_density(ty, d, var) + self.log_window_m
            if prior.confident:
                cost = cost - llr
            feasible = llr >= -0.5 * self.gate_range
        return cost, feasible

    def _match_slots(
        self, tracks: list[Track], ty: int, prior: DistancePrior | None, slots: np.ndarray
    ) -> list[tuple[Track, int]]:
        """(track, slot) pairs filling reflector ``slots`` of type ``ty`` (GNN)."""
        if not tracks or not len(slots):
            return []
        cost, feasible = self._slot_costs(tracks, ty, prior)
        cost, feasible = cost[:, slots], feasible[:, slots]
        rows, cols = linear_sum_assignment(np.where(feasible, cost, INFEASIBLE))
        return [
            (tracks[r], int(slots[c])) for r, c in zip(rows, cols, strict=True) if feasible[r, c]
        ]

    def select(self, tracks: list[Track], prior: DistancePrior | None) -> None:
        """Mark, per type, the persistent tracks most like its reflectors as reported."""
        for ty, cap in enumerate(self.capacity):
            pool = [t for t in tracks if t.type_index == ty and t.persistent]
            pairs = self._match_slots(pool, ty, prior, np.arange(cap))
            chosen = {id(t): slot for t, slot in pairs}
            for t in pool:
                t.slot = chosen.get(id(t), -1)

    def fingerprint(self, tracks: list[Track], prior: DistancePrior | None) -> Fingerprint:
        """The reported tracks' distances per type; free slots filled by tentative tracks."""
        chosen_by_type, fresh_by_type = [], []
        for ty, cap in enumerate(self.capacity):
            sel = [t for t in tracks if t.type_index == ty and t.selected]
            chosen, flags = sel, [t.fresh for t in sel]
            if len(sel) < cap:
                # Free slots: tentative tracks, flagged not fresh. With a prior, the free slots
                # are the reflectors no reported track matches.
                tent = [t for t in tracks if t.type_index == ty and not t.persistent]
                free = np.arange(cap - len(sel))
                if prior is not None:
                    taken = {t.slot for t in sel}
                    free = np.array([m for m in range(cap) if m not in taken], dtype=int)
                extra = [t for t, _ in self._match_slots(tent, ty, prior, free)]
                chosen = sel + extra
                flags = flags + [False] * len(extra)
            chosen_by_type.append(chosen)
            fresh_by_type.append(flags)
        return tracks_fingerprint(self.type_names, chosen_by_type, fresh_by_type)
