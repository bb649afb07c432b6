"""Which mapped reflector is not where the map says? A per-reflector consistency check.

A reflector that was knocked, re-mounted, covered or removed keeps its surveyed position in
the map, so every frame it is visible from the pose the *other* reflectors agree on, the radar
should see a return of its type at the predicted distance and does not. The monitor counts, on
frames where the localiser vouches for its estimate (converged), whether each reflector that
should be visible (in range, its pattern facing the radar within ``min_gain``, no obstacle on
the line of sight) has a detection of its type within ``gate_sigmas`` standard deviations of
the predicted distance (the radar's range noise and a converged estimate's error: about 0.1 m;
distances of any type count, because a weak return's RCS estimate scatters across the types'
windows). The miss share (a running mean over its first ``window_frames``
visible frames, then exponentially weighted over about that many) above ``suspect_share``,
after at least ``min_visible_frames`` visible frames, names the reflector a suspect; below
``clear_share`` clears it (hysteresis). A reflector moved by less than a few gate widths
still answers inside or near the gate in many frames: the displacement test names it when
a fixed move explains its returns over the frames significantly better than none, and better
than any other reflector's move explains theirs. By default
(:mod:`lrp_gym.localization.displacement_glrt`) every return near the reflector's distance is
a candidate for its own, because the nearest one is often the room's, weighed by how well its
radial velocity fits the reflector's line of sight; the parity test of
:mod:`lrp_gym.localization.displacement_test`, which confirms a name, fits the nearest return
whose radial velocity fits, with the estimate's position error projected out. With
``mask_excess_db`` set (off by default), a frame does not judge a reflector that a much
stronger return near its distance may hide. The null case is the radar's own miss rate (about 5 %
per frame for a visible trihedral in the paper room). The gate must be tight: a frame has about ten
reflector-like returns (ghosts via walls and ceiling, room corners) between 2 and 6 m, so a
moved reflector's predicted distance still finds some return within 0.1 m in about half of
the frames; measured on the patrol, a reflector moved by 0.5 m misses the 0.1 m gate in 41 %
of its visible frames, one in place in 2 %, hence ``suspect_share`` 0.25.

A miss share alone cannot tell one reflector from a common cause: with a share of the
detections dropped at random (or the radar covered, or interference) every reflector's miss
share is the drop rate. So a reflector is a suspect on misses only if it also misses more
often than its peers in the same frames: each reflector keeps, with its own running mean and
weights, the *common share* (the mean miss of the other judged reflectors not under
suspicion, frame by frame), and its excess over it must pass a one-sided two-proportion
z-test at ``excess_z`` standard errors (the null: it misses at its peers' rate). A frame in
which it is judged alone says nothing either way. With dropped detections a missing
reflector's nearest return is a neighbour's or a ghost's, within twice the gate and on one
side, so the old bias test (``bias_m``, now off by default) named
a reflector under a common cause; the displacement test takes only residuals within its gate
and removes the position error, which cut those false names (docs/robustness.md).

The localiser may then leave the suspects out of its measurement model
(``drop_suspects``): a moved reflector's returns stop pulling the estimate, and a user
surveying the room learns which reflector to check (``info["suspect_reflectors"]``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from lrp_gym.config.localization import LocalizationConfig
from lrp_gym.config.room_changes import ReflectorMonitorConfig
from lrp_gym.localization.displacement_glrt import DisplacementGlrt
from lrp_gym.localization.displacement_test import DisplacementTest
from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.localization.monitor_frame import (
    MonitorFrame,
    doppler_residuals,
    masked_by_stronger,
    nearest_residuals,
)
from lrp_gym.localization.pose_estimate import PoseEstimate
from lrp_gym.localization.visibility import RadarLink
from lrp_gym.radar.detections import Detections
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.reflector_view import reflector_view
from lrp_gym.world.world import World


@dataclass
class ReflectorMonitor:
    """Miss statistics of every mapped reflector (one robot's; reset per episode).

    Parameters
    ----------
    world : World
        The surveyed map (layout, room, radar height).
    cfg : ReflectorMonitorConfig
    max_range_m : float
        Farthest distance the radar reports a reflector at.

    Attributes
    ----------
    miss_share, common_share : ndarray (M,)
        Running means, over each reflector's judged frames, of its misses and of its peers'
        mean miss in those frames.
    null_var : ndarray (M,)
        The running mean's squared weights times each frame's ``1 + 1/k`` (k peers): the
        excess's variance over ``p (1 - p)`` if every reflector missed at one rate p.
    mean_residual_m : ndarray (M,)
        Running mean of the nearest return minus the prediction (within twice the gate; kept
        only with the bias test, ``bias_m``).
    """

    world: World
    cfg: ReflectorMonitorConfig
    max_range_m: float

    def __post_init__(self) -> None:
        m = len(self.world.layout)
        self.miss_share = np.zeros(m)
        self.common_share = np.zeros(m)
        self.null_var = np.zeros(m)
        self.mean_residual_m = np.zeros(m)
        self.visible_frames = np.zeros(m, dtype=np.int64)
        self.suspect = np.zeros(m, dtype=bool)
        cfg = self.cfg
        # The parity test runs alone, or beside the likelihood test to confirm its names.
        parity = cfg.displacement_test == "parity" or cfg.displacement_confirm_chi2 is not None
        self.parity = (
            DisplacementTest(
                m, cfg.displacement_std_m, cfg.displacement_gate_m, cfg.displacement_window_frames
            )
            if parity
            else None
        )
        self.displacement: DisplacementTest | DisplacementGlrt = (
            self.parity
            if cfg.displacement_test == "parity"
            else DisplacementGlrt(
                m,
                cfg.displacement_std_m,
                cfg.displacement_max_m,
                cfg.displacement_detection_probability,
                cfg.displacement_clutter_per_m,
                cfg.displacement_window_frames,
                doppler_std_mps=cfg.displacement_doppler_std_mps,
                max_velocity_mps=self.world.fmcw.max_velocity_mps,
            )
        )

    def reset(self) -> None:
        self.miss_share[:] = 0.0
        self.common_share[:] = 0.0
        self.null_var[:] = 0.0
        self.mean_residual_m[:] = 0.0
        self.visible_frames[:] = 0
        self.suspect[:] = False
        self.displacement.reset()
        if self.parity is not None and self.parity is not self.displacement:
            self.parity.reset()

    @property
    def suspects(self) -> tuple[int, ...]:
        """Indices (into the layout) of the reflectors currently suspected."""
        return tuple(int(i) for i in np.flatnonzero(self.suspect))

    def visible(self, xy: np.ndarray) -> np.ndarray:
        """Boolean (M,): which reflectors the radar at floor position ``xy`` should see."""
        return self._expected(xy)[1]

    def _expected(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Predicted distances (M,) from floor position ``xy`` and which reflectors the radar
        should see there (in range, facing it within ``min_gain``, no obstacle between)."""
        return self._geometry(xy)[:2]

    def _geometry(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`_expected`, the horizontal part (M, 2) of each unit vector from the radar
        to the reflector (how a reflector's distance changes as it moves) and each one's RCS
        at this aspect (M,), m^2."""
        world, xy = self.world, np.asarray(xy, dtype=float)
        # The monitor's own range (the tracker's) and pattern threshold on the shared view.
        view = reflector_view(world.room, world.layout, world.mount_height_m, np.inf, xy[None])
        dist, gain = view.dist_m[:, 0], view.gain[:, 0]
        bearing = (world.layout.positions_m[:, :2] - xy) / np.maximum(dist, 1e-9)[:, None]
        ok = view.in_view[:, 0] & (gain >= self.cfg.min_gain) & (dist <= self.max_range_m)
        return dist, ok, bearing, gain * world.layout.rcs_m2

    def update(
        self,
        estimate: PoseEstimate,
        gated: Fingerprint,
        others_m: np.ndarray | None = None,
        speed_mps: float | None = None,
        detections: Detections | None = None,
    ) -> bool:
        """Add one frame (``gated``: this frame's detections in each type's window); returns
        whether the suspect set changed. Frames without a converged estimate are skipped.
        ``others_m``: predicted distances of other known static returns (the clutter map's
        points), which a reflector's return merges with just as with another reflector's.
        ``speed_mps``: the robot's signed forward (wheel) speed, for the Doppler.
        ``detections``: all of the frame's detections, whose RCS tells where a much stronger
        return may hide a reflector."""
        frame = self.observe(estimate, gated, others_m, speed_mps, detections)
        return False if frame is None else self.accumulate(frame)

    def observe(
        self,
        estimate: PoseEstimate,
        gated: Fingerprint,
        others_m: np.ndarray | None = None,
        speed_mps: float | None = None,
        detections: Detections | None = None,
    ) -> MonitorFrame | None:
        """One frame's evidence, without adding it (see :meth:`update`); None when the
        frame judges no reflector (or is not converged)."""
        if not estimate.settled:
            return None
        predicted, seen, bearing, rcs_m2 = self._geometry(estimate.pose[:2])
        if not seen.any():
            return None
        # A reflector whose distance is within two range cells of another one's shares its
        # returns (the peaks merge or shift): its misses there say nothing about it.
        gap = np.abs(predicted[:, None] - predicted[None, :])
        np.fill_diagonal(gap, np.inf)
        if others_m is not None and len(others_m):
            gap = np.hstack([gap, np.abs(predicted[:, None] - np.asarray(others_m)[None, :])])
        seen &= gap.min(axis=1) >= 2.0 * self.world.fmcw.range_resolution_m
        cfg = self.cfg
        if detections is not None and cfg.mask_excess_db is not None:
            # Nor does a frame in which a much stronger return may hide the reflector.
            rcs_dbsm = 10.0 * np.log10(np.maximum(rcs_m2, 1e-12))
            gate_m = cfg.gate_sigmas * cfg.range_std_m
            seen &= ~masked_by_stronger(
                predicted, rcs_dbsm, detections, gate_m, cfg.mask_window_m, cfg.mask_excess_db
            )
        if not seen.any():
            return None
        z = np.concatenate([np.zeros(0), *gated.distances_m])
        vel = velocity_xy = expected_v = None
        if gated.velocities_mps is not None and speed_mps is not None:
            vel = np.concatenate([np.zeros(0), *gated.velocities_mps])
            heading = float(estimate.pose[2])
            velocity_xy = float(speed_mps) * np.array([np.cos(heading), np.sin(heading)])
            expected_v = -bearing @ velocity_xy  # a static point's radial velocity
        residual = nearest_residuals(predicted, z)
        parity = None
        v_std = self.cfg.displacement_doppler_std_mps
        if vel is not None and v_std > 0 and len(z):
            parity = doppler_residuals(predicted, z, vel, expected_v, 3.0 * v_std)
        return MonitorFrame(
            seen, residual, bearing, predicted, z, vel, velocity_xy, expected_v, parity
        )

    def accumulate(self, frame: MonitorFrame) -> bool:
        """Add one frame's evidence (what :meth:`observe` returns); returns whether the
        suspect set changed."""
        cfg = self.cfg
        seen, residual = frame.judged, frame.residual_m
        if frame.bearing is not None and cfg.displacement_chi2 is not None:
            self._add_displacement(frame)
        # Not widened by the estimate's covariance: that counts the particle set's tails
        # (about 6 cm when converged, while the error is 1-2 cm) and would let a moved
        # reflector's distance find a stray return in most frames.
        gate_m = cfg.gate_sigmas * cfg.range_std_m
        missed = (seen & (np.abs(residual) > gate_m)).astype(float)
        # The frame's common miss rate as each reflector sees it: the mean miss of the other
        # judged reflectors not under suspicion (a suspect's misses are its own). Without any,
        # the reflector's own miss stands in: the frame then says nothing for or against it.
        peers = seen & ~self.suspect
        k = np.count_nonzero(peers) - peers  # peers other than the reflector itself
        others = np.divide(
            np.sum(missed[peers]) - missed * peers, k, out=missed.copy(), where=k > 0
        )
        # Per-frame variance of (own miss - the others' mean) under the null hypothesis of one
        # common miss probability p, in units of p (1 - p): 1 + 1/k, none without peers.
        var_unit = np.where(k > 0, 1.0 + 1.0 / np.maximum(k, 1), 0.0)
        self.visible_frames[seen] += 1
        # A running mean until 1/k falls below 1/window (bias-corrected average), then EWMA;
        # the common share and the residual follow the reflector's own frames and weights.
        alpha = 1.0 / np.clip(self.visible_frames, 1, cfg.window_frames)
        a = alpha[seen]
        self.miss_share[seen] += a * (missed[seen] - self.miss_share[seen])
        self.common_share[seen] += a * (others[seen] - self.common_share[seen])
        self.null_var[seen] = (1.0 - a) ** 2 * self.null_var[seen] + a**2 * var_unit[seen]
        if cfg.bias_m is not None:
            # The bias test's residual mean, over the frames within twice the gate: a reflector
            # moved by a few gate widths answers near its prediction, always on one side.
            near = seen & (np.abs(residual) <= 2.0 * gate_m)
            self.mean_residual_m[near] += alpha[near] * (
                residual[near] - self.mean_residual_m[near]
            )
        before = self.suspect.copy()
        ready = self.visible_frames >= cfg.min_visible_frames
        biased = self._biased()
        # On misses: often (suspect_share) and more often than its peers (the excess test); a
        # suspect is cleared once it misses rarely again or no more often than its peers.
        excess = self.miss_share - self.common_share
        on_misses = (self.miss_share >= cfg.suspect_share) & self._excess_significant(excess)
        self.suspect |= ready & (on_misses | biased)
        self.suspect &= ((self.miss_share > cfg.clear_share) & (excess > 0.0)) | biased
        return bool(np.any(before != self.suspect))

    def _add_displacement(self, frame: MonitorFrame) -> None:
        if self.parity is not None:
            # Fault exclusion: a suspect's residuals would spread into its peers' parity.
            r = frame.residual_m if frame.parity_residual_m is None else frame.parity_residual_m
            self.parity.add(frame.judged & ~self.suspect, r, frame.bearing)
        if isinstance(self.displacement, DisplacementGlrt) and frame.predicted_m is not None:
            # A suspect keeps being judged (its statistic holds it, with hysteresis): without
            # a projection, its residuals do not spread into its peers'.
            self.displacement.add(
                frame.judged,
                frame.predicted_m,
                frame.distances_m,
                frame.bearing,
                frame.velocities_mps,
                frame.velocity_xy,
                frame.expected_velocity_mps,
            )

    def _biased(self) -> np.ndarray:
        """Boolean (M,): suspects on their residuals, not their misses. The displacement test
        names the reflector whose fitted move is significant and ahead of the others' (the
        likelihood test's leader confirmed by the parity test, ``displacement_confirm_chi2``),
        and keeps it while its statistic stays above half the threshold (hysteresis); the older
        bias test (``bias_m``, off by default) asks for a one-sided mean residual."""
        cfg = self.cfg
        out = np.zeros(len(self.suspect), dtype=bool)
        if cfg.bias_m is not None:
            out |= np.abs(self.mean_residual_m) >= cfg.bias_m
        if cfg.displacement_chi2 is not None:
            t = self.displacement.statistic
            out |= self.suspect & (t >= 0.5 * cfg.displacement_chi2)
            j = self.displacement.leader(cfg.displacement_chi2, cfg.displacement_lead, t)
            confirm = self.parity is not None and self.parity is not self.displacement
            if j is not None and confirm:
                if self.parity.statistic[j] < cfg.displacement_confirm_chi2:
                    j = None
            if j is not None:
                out[j] = True
        return out

    def _excess_significant(self, excess: np.ndarray) -> np.ndarray:
        """Boolean (M,): ``excess`` (miss share minus common share) is at least ``excess_z``
        standard errors.

        A one-sided two-proportion z-test on the paired running means. Under the null
        hypothesis that a reflector misses at its peers' rate p, the excess has variance
        ``p (1 - p) * null_var`` (``null_var``: the running mean's squared weights times each
        frame's ``1 + 1/k``). p is the common share, not the pooled one: pooled with a moved
        reflector's own misses it would inflate the variance of the clean room's few % and
        delay the naming. The frames are taken as independent and the running means are
        tested every frame, an episode long: hence ``excess_z`` 4, not 2.
        """
        p = self.common_share
        return excess >= self.cfg.excess_z * np.sqrt(p * (1.0 - p) * self.null_var)


def model_without(
    world: World,
    cfg: LocalizationConfig,
    suspects: tuple[int, ...],
    link: RadarLink | None = None,
) -> FingerprintModel:
    """The localisers' measurement model of ``world`` (with the radar ``link``) without the
    reflectors ``suspects`` (their returns become clutter); the full model when fewer than
    three would remain."""
    layout = world.layout
    if len(layout) - len(suspects) < 3:
        suspects = ()
    keep = np.setdiff1d(np.arange(len(layout)), suspects)
    reduced = replace(
        layout,
        positions_m=layout.positions_m[keep],
        type_index=layout.type_index[keep],
        axes=layout.axes[keep],
    )
    link = None if link is None else link.of_reflectors(keep)
    return FingerprintModel.for_world(replace(world, layout=reduced), cfg, link)
