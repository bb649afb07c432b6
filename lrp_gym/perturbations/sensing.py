"""Perturbations of what the radar sees: shadowing, missed detections, clutter, interference."""

from __future__ import annotations

import numpy as np

from lrp_gym.config.perturbations import (
    ClutterConfig,
    InterferenceConfig,
    MissedDetectionsConfig,
    ShadowingConfig,
)
from lrp_gym.perturbations.base import (
    FrameContext,
    Perturbation,
    Scatterers,
    merge_hidden,
    merge_scatterers,
    peak_rcs_dbsm,
    register,
)
from lrp_gym.radar.detections import Detections
from lrp_gym.world.room import Box, Room


@register
class Shadowing(Perturbation):
    """Reflectors hidden for a number of frames.

    One event per episode starts at a frame drawn from ``start_frames`` and hides
    ``reflectors`` randomly chosen reflectors (all their paths, multipath included).

    - ``mode="static"``: an obstacle stands in the line of sight for exactly ``frames`` frames.
    - ``mode="person"``: a person-sized box (``person_size_m``) walks across the line of sight
      from the robot to the reflector, at the speed that makes its width pass in ``frames``
      frames; the reflector is hidden while the box actually cuts the line of sight
      (geometry, so the robot's own motion changes the exact duration).

    Severity: ``frames = max(1, round(40 * severity))`` unless ``frames`` is given
    (severity 0.25 -> 10 frames).
    """

    name = "shadowing"
    cfg: ShadowingConfig

    def __init__(self, cfg, world) -> None:
        super().__init__(cfg, world)
        self.frames = (
            int(cfg.frames) if cfg.frames is not None else max(1, round(40 * self.severity))
        )
        self.start = 0
        self.targets = np.zeros(0, int)
        self._persons: list[tuple[np.ndarray, np.ndarray]] = []  # (start centre, velocity)

    def on_reset(self, ctx: FrameContext, rng: np.random.Generator) -> None:
        lo, hi = sorted(self.cfg.start_frames)
        self.start = int(rng.integers(lo, hi + 1))
        m = len(ctx.sensor_layout)
        self.targets = rng.choice(m, min(self.cfg.reflectors, m), replace=False)
        self._persons = []

    def _person_hidden(self, ctx: FrameContext, rng: np.random.Generator) -> np.ndarray:
        radar = ctx.radar_position_m
        pos = ctx.sensor_layout.positions_m
        size = np.asarray(self.cfg.person_size_m, float)
        if ctx.frame == self.start:  # place the walkers relative to today's line of sight
            self._persons = []
            for j in self.targets:
                los = pos[j, :2] - radar[:2]
                dist = max(float(np.linalg.norm(los)), 1e-6)
                u = los / dist
                # Where the line of sight is still below head height.
                rise = (pos[j, 2] - radar[2]) / dist
                reach = (size[2] - radar[2]) / rise if rise > 0 else dist
                frac = rng.uniform(0.2, 0.8) * min(reach, dist)
                normal = np.array([-u[1], u[0]]) * rng.choice([-1.0, 1.0])
                speed = size[0] / (self.frames * ctx.dt_s)
                centre = radar[:2] + frac * u - normal * size[0] * 0.75  # just off the line
                self._persons.append((centre, normal * speed))
        hidden = np.zeros(len(pos), bool)
        t = (ctx.frame - self.start) * ctx.dt_s
        for j, (centre, vel) in zip(self.targets, self._persons, strict=True):
            c = centre + vel * t
            box = Box(
                np.array([c[0] - size[0] / 2, c[1] - size[1] / 2, 0.0]),
                np.array([c[0] + size[0] / 2, c[1] + size[1] / 2, size[2]]),
            )
            room = Room(self.world.room.size_m, (box,))
            hidden[j] = bool(room.segments_blocked(radar, pos[j]))
        return hidden

    def radar_inputs(self, ctx, hidden, scatterers, rng):
        if ctx.frame < self.start:
            return hidden, scatterers
        if self.cfg.mode == "static":
            if ctx.frame >= self.start + self.frames:
                return hidden, scatterers
            mask = np.zeros(len(ctx.sensor_layout), bool)
            mask[self.targets] = True
        else:
            # The walker has crossed well before three nominal durations are over.
            if ctx.frame >= self.start + 3 * self.frames + 2:
                return hidden, scatterers
            mask = self._person_hidden(ctx, rng)
        return merge_hidden(hidden, mask), scatterers


@register
class MissedDetections(Perturbation):
    """Each detection is dropped independently with probability ``probability``.

    Severity: ``probability = severity`` unless given.
    """

    name = "missed_detections"
    cfg: MissedDetectionsConfig

    def __init__(self, cfg, world) -> None:
        super().__init__(cfg, world)
        self.probability = float(cfg.probability if cfg.probability is not None else self.severity)

    def filter_detections(self, ctx, detections, rng):
        if not len(detections) or self.probability <= 0.0:
            return detections
        return detections.select(rng.random(len(detections)) >= self.probability)


@register
class Clutter(Perturbation):
    """Static point scatterers with reflector-like RCS, drawn anew each episode.

    ``count`` scatterers uniform over the room volume (outside obstacles), each with the
    peak RCS of the strongest reflector type plus a uniform ``+-rcs_spread_db`` (so the
    tracker's RCS gate cannot tell them from LRPs). They are omnidirectional and shadowed by
    obstacles like any direct path.

    Severity: ``count = round(20 * severity)`` unless given.
    """

    name = "clutter"
    cfg: ClutterConfig

    def __init__(self, cfg, world) -> None:
        super().__init__(cfg, world)
        self.count = int(cfg.count if cfg.count is not None else round(20 * self.severity))
        self.positions_m = np.zeros((0, 3))
        self.rcs_m2 = np.zeros(0)

    def on_reset(self, ctx, rng):
        size = self.world.room.size_m
        p = rng.random((self.count, 3)) * size
        for box in self.world.room.obstacles:
            p = p[~box.contains(p)]
        spread = self.cfg.rcs_spread_db
        rcs_db = peak_rcs_dbsm(ctx.sensor_layout) + rng.uniform(-spread, spread, len(p))
        self.positions_m, self.rcs_m2 = p, 10.0 ** (rcs_db / 10.0)

    def radar_inputs(self, ctx, hidden, scatterers, rng):
        if not len(self.rcs_m2):
            return hidden, scatterers
        return hidden, merge_scatterers(scatterers, (self.positions_m, self.rcs_m2))


@register
class Interference(Perturbation):
    """Bursts of spurious detections from another vehicle's radar.

    A burst starts with probability ``burst_probability`` in any frame without one and lasts
    ``burst_frames`` frames; each burst frame adds ``detections_per_frame`` detections at
    uniform ranges (``min_range_m`` .. room diagonal) and radial velocities (within the
    unambiguous interval), with RCS estimates around the strongest reflector type's peak
    (``+-rcs_spread_db``) so they pass the tracker's RCS gate.

    Severity: ``burst_probability = 0.3 * severity``,
    ``detections_per_frame = 1 + round(9 * severity)`` unless given.
    """

    name = "interference"
    cfg: InterferenceConfig

    def __init__(self, cfg, world) -> None:
        super().__init__(cfg, world)
        s = self.severity
        self.burst_probability = float(
            cfg.burst_probability if cfg.burst_probability is not None else 0.3 * s
        )
        self.per_frame = int(
            cfg.detections_per_frame if cfg.detections_per_frame is not None else 1 + round(9 * s)
        )
        self.remaining = 0
        self.burst_frames: list[int] = []  # frames with a burst this episode (for tests/reports)

    def on_reset(self, ctx, rng):
        self.remaining = 0
        self.burst_frames = []

    def filter_detections(self, ctx, detections, rng):
        if self.remaining == 0 and self.burst_probability > 0.0:
            if rng.random() < self.burst_probability:
                self.remaining = self.cfg.burst_frames
        if self.remaining == 0 or self.per_frame == 0:
            return detections
        self.remaining -= 1
        self.burst_frames.append(ctx.frame)
        return Detections.concatenate([detections, self.spurious(ctx, rng)])

    def spurious(self, ctx: FrameContext, rng: np.random.Generator) -> Detections:
        """One frame of interference detections."""
        w = self.world
        fm = w.fmcw
        n = self.per_frame
        r_lo = 0.3
        r_hi = min(fm.max_range_m, w.room.diagonal_m)
        range_m = rng.uniform(r_lo, r_hi, n)
        vel = rng.uniform(-fm.max_velocity_mps, fm.max_velocity_mps, n)
        spread = self.cfg.rcs_spread_db
        rcs_dbsm = peak_rcs_dbsm(ctx.sensor_layout) + rng.uniform(-spread, spread, n)
        sensor = ctx.sensor
        # The power whose RCS estimate (the sensor's own inversion) is the drawn one.
        power_w = 10.0 ** ((rcs_dbsm - sensor.rcs_dbsm(np.ones(n), range_m)) / 10.0)
        peak = power_w * sensor.processor.coherent_gain2
        return Detections(
            range_m=range_m,
            velocity_mps=vel,
            power_dbm=10.0 * np.log10(power_w) + 30.0,
            rcs_dbsm=rcs_dbsm,
            snr_db=10.0 * np.log10(peak / sensor.noise_cell),
        )


__all__ = ["Clutter", "Interference", "MissedDetections", "Shadowing", "Scatterers"]
