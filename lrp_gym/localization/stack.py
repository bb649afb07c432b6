"""One radar frame, one object: radar, tracker, localiser and look-up table in the order the data allow.

:class:`LocalizationStack` owns the four stages and the order between them; everything that
drives a robot frame by frame (the env, ``reproduce-paper``, ``lrp-gym track``) calls its
:meth:`~LocalizationStack.step` and reads a :class:`FrameResult`.

The order depends on what the localiser weighs (``localization.measurements``):

- ``detections`` (default): the localiser needs no tracker, so it runs first, on the
  detections that pass a reflector type's RCS/range window; its posterior of *this* frame then
  tells the tracker which track is which reflector (map-aided identification);
- ``tracks``: the tracker runs first, identified by the localiser's cloud of the *previous*
  frame moved by the odometry (so its output is not built from its own detections fed
  back), then the localiser weighs the tracker's fingerprint.

The look-up table, when there is one, positions the tracker's fingerprint (no heading: the
localiser's completes it). Last, the reflector monitor checks every mapped reflector against
the estimate and may take suspects out of the localiser's map (``reflector_monitor.py``).
"""

from __future__ import annotations

import copy
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from lrp_gym.config import ScenarioConfig
from lrp_gym.localization.clutter_map import ClutterMap
from lrp_gym.localization.factory import Localizer, make_localizer, measured_mixture, radar_link
from lrp_gym.localization.frame_result import FrameResult
from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.localization.lut import LookupTable
from lrp_gym.localization.pose_estimate import PoseEstimate
from lrp_gym.localization.reflector_monitor import ReflectorMonitor, model_without
from lrp_gym.radar.detections import Detections
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.tracking.prior import DistancePrior
from lrp_gym.tracking.range_prediction import EgoMotion
from lrp_gym.tracking.tracker import LrpTracker
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.robot import apply_odometry
from lrp_gym.world.world import World

#: ``filter_detections`` hook of :meth:`LocalizationStack.step`: the radar's detections in,
#: the detections the tracker and the localiser receive out.
DetectionFilter = Callable[[Detections], Detections]


class LocalizationStack:
    """Radar, LRP tracker, localiser and optional look-up table of one robot, frame by frame.

    Parameters
    ----------
    world : World
        The surveyed world: the map the tracker and the localiser use.
    sensor : RadarSensor
        The radar on the surveyed layout (see :meth:`set_radar_layout` for another one).
    tracker : LrpTracker
    localizer : Amcl or GridFilter
    lut : LookupTable, optional
        With it, the consumer's estimate is the table's position (see :class:`FrameResult`).
    dt_s : float
        Frame period (the tracker's prediction step).
    measurements : {"detections", "tracks"}
        What the localiser weighs; it fixes the order (module docstring).
    map_aided : bool
        Identify the reflectors with the localiser's cloud (else RCS, motion and track
        quality only, as in the paper).
    use_ego : bool
        Give the tracker the odometry (static-point prediction, Doppler bound); else the
        paper's constant-velocity model.

    Notes
    -----
    Per-robot state, all reset by :meth:`reset` (what a batch of robots has one of each):

    - the tracker's tracks (:class:`LrpTracker`) and the window test of its last frame;
    - the localiser's particles ``(P, 3)`` and weights ``(P,)`` (AMCL; a belief grid for the
      grid filter), its recovery averages and the predicted cloud of its last update;
    - :attr:`settled`, the previous frame's :attr:`PoseEstimate.settled`; with ``tracks`` it
      decides whether the cloud may rank the tracks or only veto them;
    - :attr:`sensor`, the radar of this episode (the surveyed layout, or a moved one);
    - the reflector monitor's statistics, and which map (without suspects) the localiser uses.

    Everything else (world, configuration, look-up table, the surveyed sensor) is shared and
    read-only. No state is keyed on the identity of an input object: every value a stage
    reuses within a frame is passed along explicitly.
    """

    def __init__(
        self,
        world: World,
        sensor: RadarSensor,
        tracker: LrpTracker,
        localizer: Localizer,
        lut: LookupTable | None = None,
        *,
        dt_s: float,
        measurements: str = "detections",
        map_aided: bool = True,
        use_ego: bool = True,
        monitor: ReflectorMonitor | None = None,
        clutter_map: ClutterMap | None = None,
    ) -> None:
        if measurements not in ("detections", "tracks"):
            raise ValueError(
                f"localization.measurements must be detections or tracks, got {measurements!r}"
            )
        if not dt_s > 0:
            raise ValueError(f"task.frame_period_s must be positive, got {dt_s}")
        self.world = world
        self.surveyed_sensor = sensor
        self.sensor = sensor
        self.tracker = tracker
        self.localizer = localizer
        self.lut = lut
        self.dt_s = float(dt_s)
        self.measurements = measurements
        self.map_aided = map_aided
        self.use_ego = use_ego
        self.settled = False
        self.monitor = monitor
        self.clutter_map = clutter_map
        # The surveyed map's models by the suspects they drop (read-only, shared by spawns).
        self._models: dict[tuple[int, ...], FingerprintModel] = {(): localizer.model}

    @classmethod
    def from_config(
        cls,
        world: World,
        cfg: ScenarioConfig,
        *,
        map_aided: bool = True,
        use_ego: bool = True,
    ) -> LocalizationStack:
        """The stack a validated scenario describes.

        The localiser follows ``localization.method`` (``grid``: the histogram filter, else
        AMCL); ``method: lut`` adds the look-up table (AMCL still runs: its cloud identifies
        the reflectors and its heading completes the table's position).
        """
        loc = cfg.localization
        lut = None
        if loc.method == "lut":
            lut = LookupTable(world, loc.lut_resolution_m, loc.lut_grid_m)
        tracker = LrpTracker.from_world(world, cfg.tracking)
        sensor = RadarSensor(world, cfg.radar)
        mon, max_r = loc.reflector_monitor, float(tracker.classifier.max_range_m)
        monitor = ReflectorMonitor(world, mon, max_r) if mon.enabled else None
        return cls(
            world,
            sensor,
            tracker,
            make_localizer(world, measured_mixture(cfg), radar_link(cfg, sensor)),
            lut,
            dt_s=cfg.task.frame_period_s,
            measurements=loc.measurements,
            map_aided=map_aided,
            use_ego=use_ego,
            monitor=monitor,
            clutter_map=ClutterMap(world, loc.clutter_map) if loc.clutter_map.enabled else None,
        )

    def spawn(self) -> LocalizationStack:
        """Another robot's stack on the same map: the read-only parts shared (world, radar
        model, measurement models, grids, look-up table), the per-robot state of the class
        notes its own (:meth:`reset` it before use)."""
        new = copy.copy(self)
        # A shallow copy: the radar's per-frame attributes (last paths) are then its own.
        new.surveyed_sensor = new.sensor = copy.copy(self.surveyed_sensor)
        new.tracker = copy.copy(self.tracker)  # its state is reset below
        new.tracker.reset()
        new.localizer = self.localizer.spawn()
        new.localizer.model = self._models[()]
        new.settled = False
        if self.monitor is not None:
            new.monitor = replace(self.monitor)  # fresh statistics (see __post_init__)
        new.clutter_map = self.clutter_map and replace(self.clutter_map)  # no points yet
        return new

    # ------------------------------------------------------------------ per-robot state
    def reset(self, rng: np.random.Generator, known_pose: np.ndarray | None = None) -> None:
        """Start a run: no tracks, a fresh cloud, the surveyed radar.

        Parameters
        ----------
        rng : numpy.random.Generator
            The localiser's initial cloud is drawn from it.
        known_pose : ndarray (3,), optional
            Start pose for a Gaussian start (``localization.init: gaussian``); None spreads
            the cloud over the room (global localisation).
        """
        self.tracker.reset()
        self.localizer.model = self._models[()]
        self.localizer.reset(rng, known_pose)
        self.settled = False
        self.sensor = self.surveyed_sensor
        if self.monitor is not None:
            self.monitor.reset()
        if self.clutter_map is not None:
            self.clutter_map.reset()

    def set_radar_layout(self, layout: ReflectorLayout) -> None:
        """Let the radar see ``layout`` until the next :meth:`reset`; the map stays surveyed.

        For a perturbed episode (a displaced reflector): the tracker and the localiser keep
        the surveyed layout, only the radar channel changes.
        """
        if layout is self.world.layout:
            self.sensor = self.surveyed_sensor
        else:
            world = replace(self.world, layout=layout)
            self.sensor = RadarSensor(world, self.surveyed_sensor.config)

    # ------------------------------------------------------------------ one frame
    def step(
        self,
        true_pose: np.ndarray,
        velocity_xy: np.ndarray,
        odometry: np.ndarray,
        rng: np.random.Generator,
        *,
        sensing_rng: np.random.Generator | None = None,
        hidden: np.ndarray | None = None,
        extra_scatterers: tuple[np.ndarray, np.ndarray] | None = None,
        filter_detections: DetectionFilter | None = None,
    ) -> FrameResult:
        """One radar frame at the true pose, through every stage.

        Parameters
        ----------
        true_pose : ndarray (3,)
            Where the robot really is (x_m, y_m, theta_rad): where the radar measures.
        velocity_xy : ndarray (2,)
            The robot's true velocity (m/s), for the Doppler and the wheel speed.
        odometry : ndarray (3,)
            The reported odometry ``(rot1, trans, rot2)`` since the previous frame (zeros in
            the first), e.g. from :func:`~lrp_gym.world.robot.noisy_odometry`.
        rng, sensing_rng : numpy.random.Generator
            The localiser's draws; the radar noise (default: ``rng``). The tracker draws none.
        hidden, extra_scatterers
            Passed to :meth:`RadarSensor.measure` (hidden reflectors, extra scatterers).
        filter_detections : callable, optional
            Applied to the detections before the tracker sees them (drops or additions).
        """
        t0 = time.perf_counter()
        radar_rng = rng if sensing_rng is None else sensing_rng
        detections = self.measure(true_pose, velocity_xy, radar_rng, hidden, extra_scatterers)
        if filter_detections is not None:
            detections = filter_detections(detections)
        radar_s = time.perf_counter() - t0
        ego = EgoMotion.from_velocity(velocity_xy, true_pose[2], odometry)
        result = self.localize(detections, ego, rng)
        return replace(result, elapsed_s={"radar": radar_s, **result.elapsed_s})

    def measure(
        self,
        true_pose: np.ndarray,
        velocity_xy: np.ndarray,
        rng: np.random.Generator,
        hidden: np.ndarray | None = None,
        extra_scatterers: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> Detections:
        """The radar stage alone: this episode's sensor at the true pose (see :meth:`step`)."""
        return self.sensor.measure(
            true_pose, velocity_xy, rng, hidden=hidden, extra_scatterers=extra_scatterers
        )

    def localize(
        self, frame: Detections | Fingerprint, ego: EgoMotion, rng: np.random.Generator
    ) -> FrameResult:
        """The stages after the radar, on given detections or a given fingerprint.

        With :class:`Detections` (e.g. another stack's radar frame, or a radar frame measured
        before the odometry was drawn): tracker and localiser in the configured order. With a
        :class:`Fingerprint` (e.g. exact distances): the localiser weighs it directly.
        """
        t0 = time.perf_counter()
        if isinstance(frame, Fingerprint):
            detections, fingerprint = None, frame
            estimate = self.localizer.update(ego.odometry, frame, rng)
        else:
            detections = frame
            fingerprint, estimate = self._track_and_localize(frame, ego, rng)
        self.settled = bool(estimate.settled)
        suspects = () if detections is None else self._check_reflectors(estimate, ego, detections)
        t1 = time.perf_counter()
        lut_estimate, pose_estimate = self._with_lut(fingerprint, estimate)
        elapsed = {"tracking_localization": t1 - t0, "lut": time.perf_counter() - t1}
        return FrameResult(
            detections, fingerprint, estimate, lut_estimate, pose_estimate, elapsed, suspects
        )

    def _check_reflectors(
        self, estimate: PoseEstimate, ego: EgoMotion, detections: Detections
    ) -> tuple[int, ...]:
        """The reflector monitor on this frame; new suspects leave the localiser's map."""
        monitor = self.monitor
        if monitor is None:
            return ()
        gated = self.tracker.gated_fingerprint()
        cmap = self.clutter_map  # its points' returns merge with a reflector's as another's do
        others = None if cmap is None else cmap.predicted_m(estimate.pose[:2])
        changed = monitor.update(estimate, gated, others, ego.speed_mps, detections)
        if changed and monitor.cfg.drop_suspects:
            self.drop_reflectors(monitor.suspects)
        return monitor.suspects

    def drop_reflectors(self, suspects: tuple[int, ...]) -> None:
        """Give the localiser the map without the reflectors ``suspects`` (layout indices;
        ``()``: the full map), built from the full model whatever the current one drops."""
        if suspects not in self._models:
            link = self._models[()].link
            self._models[suspects] = model_without(self.world, self.localizer.cfg, suspects, link)
        self.localizer.model = self._models[suspects]

    # ------------------------------------------------------------------ internals
    def _with_lut(
        self, fingerprint: Fingerprint, estimate: PoseEstimate
    ) -> tuple[PoseEstimate | None, PoseEstimate]:
        """(The table's answer, the consumer's estimate)."""
        if self.lut is None:
            return None, estimate
        lut_est = self.lut.query(fingerprint)
        pose = np.array([*lut_est.pose[:2], estimate.pose[2]])  # the table knows no heading
        c = lut_est.converged
        return lut_est, PoseEstimate(pose, lut_est.covariance, 0, 0.0, c, float(c), 1, c)

    def _prior(
        self, particles_xy: np.ndarray, weights: np.ndarray, confident: bool
    ) -> DistancePrior:
        """The reflector distances a cloud predicts: map-aided identification for the tracker."""
        w = self.world
        return DistancePrior.from_particles(
            w.layout, w.mount_height_m, particles_xy, weights, confident=confident
        )

    def _track_and_localize(
        self, detections: Detections, ego: EgoMotion, rng: np.random.Generator
    ) -> tuple[Fingerprint, PoseEstimate]:
        """Tracker and localiser on one frame, in the order ``measurements`` allows."""
        tracker, loc = self.tracker, self.localizer
        odometry = ego.odometry
        tracker_ego = ego if self.use_ego else None
        # Augmented MCL's fit statistic: on what the localiser weighs, or on the persistent
        # tracks, scored on the same predicted cloud once the tracker has run.
        own_fit = loc.cfg.recovery_measurements == "detections"
        if self.measurements == "detections":
            window = tracker.classifier.candidates(detections)  # one window test, used twice
            gated = tracker.gated_fingerprint(detections, window)
            weighed = self._declutter(gated, odometry)
            estimate = loc.update(
                odometry,
                weighed if weighed.count else None,
                rng,
                recovery=own_fit,
                speed_mps=ego.speed_mps,
            )
            # This frame's posterior; it ranks the tracks only once settled (right after a
            # global start its heaviest mode may be a mirror image).
            prior = None
            if self.map_aided:
                prior = self._prior(loc.particles[:, :2], loc.weights, estimate.settled)
            fingerprint = tracker.update(detections, self.dt_s, tracker_ego, prior, window)
            self._learn_clutter(estimate, gated)
        else:
            # The cloud before this frame's update, moved by the odometry.
            prior = None
            if self.map_aided:
                moved = apply_odometry(loc.particles, odometry)
                prior = self._prior(moved[:, :2], loc.weights, self.settled)
            fingerprint = tracker.update(detections, self.dt_s, tracker_ego, prior)
            weighed = self._declutter(fingerprint, odometry)
            estimate = loc.update(
                odometry, weighed if weighed.count else None, rng, recovery=own_fit
            )
            self._learn_clutter(estimate, tracker.gated_fingerprint())
        if not own_fit:
            # Tracks updated in this frame only: a coasting track follows the odometry, as a
            # lost filter's cloud does, and would keep its fit up after a kidnap.
            loc.update_recovery(
                self._declutter(tracker.persistent_fingerprint(max_misses=0), odometry)
            )
        if self.clutter_map is not None:  # after every use of the previous frame's pose
            self.clutter_map.follow(estimate.pose, estimate.settled, odometry)
        return fingerprint, estimate

    def _declutter(self, fingerprint: Fingerprint, odometry: np.ndarray) -> Fingerprint:
        """``fingerprint`` without the clutter map's returns (see ``ClutterMap.declutter``)."""
        cmap = self.clutter_map
        return fingerprint if cmap is None else cmap.declutter(fingerprint, odometry)

    def _learn_clutter(self, est: PoseEstimate, gated: Fingerprint) -> None:
        """The clutter map learns from this frame on a settled estimate."""
        if (cmap := self.clutter_map) is not None and est.settled:
            cmap.update(est.pose[:2], gated, self.localizer.model.map_return_ranges)
