"""Perturbations of the reflector layout the radar sees (the localiser keeps the surveyed one)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from lrp_gym.config.perturbations import DisplacedReflectorConfig, IncidenceAngleConfig
from lrp_gym.perturbations.base import Perturbation, register
from lrp_gym.world.reflectors import ReflectorLayout

#: displaced reflectors stay this far inside the room's walls, floor and ceiling
_WALL_MARGIN_M = 0.05


@register
class DisplacedReflector(Perturbation):
    """Reflectors moved away from their surveyed positions (bumped, re-mounted, mis-surveyed).

    Each episode ``reflectors`` randomly chosen reflectors move by ``shift_m`` in a random
    horizontal direction (kept inside the room, so a shift towards a wall may be shorter).
    The radar sees the moved reflectors; the tracker and AMCL keep the surveyed map.

    Severity: ``shift_m = 1.0 * severity`` unless given.
    """

    name = "displaced_reflector"
    cfg: DisplacedReflectorConfig

    def __init__(self, cfg, world) -> None:
        super().__init__(cfg, world)
        self.shift_m = float(cfg.shift_m if cfg.shift_m is not None else self.severity)
        self.moved = np.zeros(0, int)
        self.offsets_m = np.zeros((0, 3))

    def sensor_layout(self, layout: ReflectorLayout, rng: np.random.Generator) -> ReflectorLayout:
        m = len(layout)
        self.moved = rng.choice(m, min(self.cfg.reflectors, m), replace=False)
        phi = rng.uniform(-np.pi, np.pi, len(self.moved))
        pos = layout.positions_m.copy()
        step = self.shift_m * np.column_stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)])
        size = self.world.room.size_m
        pos[self.moved] = np.clip(pos[self.moved] + step, _WALL_MARGIN_M, size - _WALL_MARGIN_M)
        self.offsets_m = pos[self.moved] - layout.positions_m[self.moved]
        return replace(layout, positions_m=pos)


@register
class IncidenceAngle(Perturbation):
    """Reflectors with a narrower acceptance angle than the surveyed type promises.

    Every type's pattern gets ``half_angle_deg`` (-3 dB) and ``cutoff_deg`` (no return
    beyond). Severity scales the type's own angles (omnidirectional types count as
    90 deg / 180 deg): ``half = h0 (1 - 0.75 severity)``, ``cutoff = max(half,
    c0 (1 - 0.6 severity))`` (a trihedral's 40/90 deg become 10/36 deg at severity 1) unless
    given.
    """

    name = "incidence_angle"
    cfg: IncidenceAngleConfig

    def sensor_layout(self, layout: ReflectorLayout, rng: np.random.Generator) -> ReflectorLayout:
        s = self.severity
        types = []
        for t in layout.types:
            h0 = t.half_angle_deg if t.half_angle_deg is not None else 90.0
            c0 = min(t.cutoff_deg, 180.0)
            half = (
                self.cfg.half_angle_deg
                if self.cfg.half_angle_deg is not None
                else h0 * (1 - 0.75 * s)
            )
            cut = (
                self.cfg.cutoff_deg
                if self.cfg.cutoff_deg is not None
                else max(half, c0 * (1 - 0.6 * s))
            )
            types.append(replace(t, half_angle_deg=float(half), cutoff_deg=float(cut)))
        return replace(layout, types=tuple(types))
