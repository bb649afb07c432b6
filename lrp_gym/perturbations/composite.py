"""All active perturbations of an env, called in registry order."""

from __future__ import annotations

import numpy as np

from lrp_gym.config import PerturbationsConfig
from lrp_gym.perturbations.base import REGISTRY, FrameContext, Perturbation
from lrp_gym.radar.detections import Detections
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.world import World


class PerturbationSet:
    """The active perturbations of a scenario, applied hook by hook.

    Parameters
    ----------
    items : list of Perturbation
        In the order their hooks run (registry order when built by :meth:`from_config`).
    """

    def __init__(self, items: list[Perturbation]) -> None:
        self.items = list(items)

    @classmethod
    def from_config(cls, cfg: PerturbationsConfig, world: World) -> PerturbationSet:
        active = cfg.active()
        return cls([REGISTRY[name](active[name], world) for name in REGISTRY if name in active])

    def __len__(self) -> int:
        return len(self.items)

    def __getitem__(self, name: str) -> Perturbation:
        for p in self.items:
            if p.name == name:
                return p
        raise KeyError(name)

    def get(self, name: str) -> Perturbation | None:
        return next((p for p in self.items if p.name == name), None)

    # ------------------------------------------------------------------ hooks
    def reset(self, ctx: FrameContext, rng: np.random.Generator) -> ReflectorLayout:
        """Draw the episode's state; return the layout the radar sees this episode."""
        for p in self.items:
            p.on_reset(ctx, rng)
        layout = ctx.sensor_layout
        for p in self.items:
            layout = p.sensor_layout(layout, rng)
        return layout

    def move(
        self, ctx: FrameContext, odometry: np.ndarray, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """(Reported odometry, new true pose or None) after the robot moved this frame."""
        pose = None
        for p in self.items:
            odometry = p.odometry(ctx, odometry, rng)
            pose = p.teleport(ctx, rng) if pose is None else pose
        return odometry, pose

    def radar_inputs(self, ctx: FrameContext, rng: np.random.Generator):
        """``(hidden, extra_scatterers)`` keyword values for :meth:`RadarSensor.measure`."""
        hidden = scatterers = None
        for p in self.items:
            hidden, scatterers = p.radar_inputs(ctx, hidden, scatterers, rng)
        return hidden, scatterers

    def filter_detections(
        self, ctx: FrameContext, detections: Detections, rng: np.random.Generator
    ) -> Detections:
        for p in self.items:
            detections = p.filter_detections(ctx, detections, rng)
        return detections
