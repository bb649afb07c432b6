"""Perturbations of the robot's motion: odometry slip and kidnapping."""

from __future__ import annotations

import numpy as np

from lrp_gym.config.perturbations import KidnappingConfig, OdometrySlipConfig
from lrp_gym.perturbations.base import Perturbation, register


@register
class OdometrySlip(Perturbation):
    """Wheel slip and a heading bias in the odometry the robot reports.

    The reported travelled distance is ``(1 + slip)`` times the true one (wheels that spin
    more than the robot moves), and ``heading_bias_dps * dt`` is added to each frame's
    reported turn (split over rot1 and rot2). The true motion is unchanged.

    Severity: ``slip = 0.5 * severity``, ``heading_bias_dps = 20 * severity`` unless given.
    """

    name = "odometry_slip"
    cfg: OdometrySlipConfig

    def __init__(self, cfg, world) -> None:
        super().__init__(cfg, world)
        s = self.severity
        self.slip = float(cfg.slip if cfg.slip is not None else 0.5 * s)
        self.heading_bias_dps = float(
            cfg.heading_bias_dps if cfg.heading_bias_dps is not None else 20.0 * s
        )

    def odometry(self, ctx, odometry, rng):
        bias = np.deg2rad(self.heading_bias_dps) * ctx.dt_s / 2.0
        rot1, trans, rot2 = odometry
        return np.array([rot1 + bias, (1.0 + self.slip) * trans, rot2 + bias])


@register
class Kidnapping(Perturbation):
    """The robot is carried to a random free pose mid-episode; the localiser is not told.

    Once per episode, at a frame drawn from ``frames``, the true pose jumps to a pose drawn
    uniformly over the free space at least ``min_jump_m`` from the current position, with a
    uniform heading. The odometry of that frame is the robot's own motion only.
    ``kidnap_frame`` is the frame at which it happened (None before).

    Severity: ``min_jump_m = 3.0 * severity`` unless given.
    """

    name = "kidnapping"
    cfg: KidnappingConfig

    def __init__(self, cfg, world) -> None:
        super().__init__(cfg, world)
        self.min_jump_m = float(
            cfg.min_jump_m if cfg.min_jump_m is not None else 3.0 * self.severity
        )
        self.planned_frame = 0
        self.kidnap_frame: int | None = None

    def on_reset(self, ctx, rng):
        lo, hi = sorted(self.cfg.frames)
        self.planned_frame = max(1, int(rng.integers(lo, hi + 1)))
        self.kidnap_frame = None

    def teleport(self, ctx, rng):
        if ctx.frame != self.planned_frame:
            return None
        room = self.world.room
        clearance = self.world.robot.radius_m + 0.05
        for _ in range(100):
            cand = rng.random((64, 2)) * room.size_m[:2]
            ok = room.free(cand, clearance)
            ok &= np.linalg.norm(cand - ctx.pose[:2], axis=1) >= self.min_jump_m
            if ok.any():
                xy = cand[np.argmax(ok)]
                break
        else:  # no free pose that far away: jump as far as possible instead
            cand = cand[room.free(cand, clearance)]
            if not len(cand):
                return None
            xy = cand[np.argmax(np.linalg.norm(cand - ctx.pose[:2], axis=1))]
        self.kidnap_frame = ctx.frame
        return np.array([xy[0], xy[1], rng.uniform(-np.pi, np.pi)])
