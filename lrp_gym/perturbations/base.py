"""The perturbation interface: one small class per perturbation, hooks the env calls.

A perturbation sees one :class:`FrameContext` per hook call and draws all its randomness from
the generator it is given (a child of the robot's ``np_random``, spawned at each reset), so
episodes stay reproducible from the env seed and the same seed perturbs the same way whatever
the localiser draws. Every hook has a no-op default; a class overrides only those it needs.

Hook order in one env frame (see :class:`~lrp_gym.perturbations.composite.PerturbationSet`):

1. ``odometry``: change the odometry the robot reports (not its true motion);
2. ``teleport``: move the true pose without telling the localiser;
3. ``radar_inputs``: hide reflectors and add point scatterers for the radar channel;
4. ``filter_detections``: drop or add detections after the radar.

At reset: ``on_reset`` (draw the episode's state), then ``sensor_layout`` (the reflector layout
the *radar* sees; the tracker and AMCL keep the surveyed one).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from lrp_gym.config.perturbations import PerturbationConfig
from lrp_gym.radar.detections import Detections
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.world import World

Scatterers = tuple[np.ndarray, np.ndarray]


@dataclass(frozen=True)
class FrameContext:
    """What a perturbation may look at in one frame.

    Attributes
    ----------
    frame : int
        0 at reset, ``k`` during the ``k``-th step.
    pose : ndarray (3,)
        True pose (x_m, y_m, theta_rad) of the robot this frame.
    world : World
        The surveyed world (what the localiser believes).
    sensor_layout : ReflectorLayout
        The reflector layout the radar sees this episode.
    dt_s : float
        Frame period.
    sensor : RadarSensor
        The radar measuring this frame (link budget, noise level).
    """

    frame: int
    pose: np.ndarray
    world: World
    sensor_layout: ReflectorLayout
    dt_s: float
    sensor: Any

    @property
    def radar_position_m(self) -> np.ndarray:
        return self.world.radar_position(self.pose[:2])


class Perturbation:
    """Base class; subclasses set ``name`` and ``config_cls`` and override hooks.

    Parameters
    ----------
    cfg : pydantic model
        The perturbation's section of ``ScenarioConfig.perturbations``.
    world : World
        The surveyed world.
    """

    name: ClassVar[str] = ""

    def __init__(self, cfg: PerturbationConfig, world: World) -> None:
        self.cfg = cfg
        self.world = world
        self.severity = float(cfg.severity)

    def on_reset(self, ctx: FrameContext, rng: np.random.Generator) -> None:
        """Draw this episode's state (positions, event frames...)."""

    def sensor_layout(self, layout: ReflectorLayout, rng: np.random.Generator) -> ReflectorLayout:
        """The layout the radar sees this episode (default: unchanged)."""
        return layout

    def odometry(
        self, ctx: FrameContext, odometry: np.ndarray, rng: np.random.Generator
    ) -> np.ndarray:
        """The reported odometry (rot1, trans, rot2) for this frame."""
        return odometry

    def teleport(self, ctx: FrameContext, rng: np.random.Generator) -> np.ndarray | None:
        """A new true pose, or None to leave it."""
        return None

    def radar_inputs(
        self,
        ctx: FrameContext,
        hidden: np.ndarray | None,
        scatterers: Scatterers | None,
        rng: np.random.Generator,
    ) -> tuple[np.ndarray | None, Scatterers | None]:
        """Hidden-reflector mask (M,) and extra point scatterers for the radar channel."""
        return hidden, scatterers

    def filter_detections(
        self, ctx: FrameContext, detections: Detections, rng: np.random.Generator
    ) -> Detections:
        """The detections the tracker receives."""
        return detections


REGISTRY: dict[str, type[Perturbation]] = {}


def register(cls: type[Perturbation]) -> type[Perturbation]:
    """Class decorator: make a perturbation available under ``cls.name``."""
    if not cls.name or cls.name in REGISTRY:
        raise ValueError(f"perturbation name {cls.name!r} is empty or already registered")
    REGISTRY[cls.name] = cls
    return cls


def merge_hidden(hidden: np.ndarray | None, extra: np.ndarray) -> np.ndarray:
    """OR a new hidden mask into an existing one (None = nothing hidden yet)."""
    return extra if hidden is None else (hidden | extra)


def merge_scatterers(a: Scatterers | None, b: Scatterers) -> Scatterers:
    """Concatenate two sets of point scatterers."""
    if a is None:
        return b
    return np.concatenate([a[0], b[0]]), np.concatenate([a[1], b[1]])


def peak_rcs_dbsm(layout: ReflectorLayout) -> float:
    """The strongest reflector type's peak RCS: what "reflector-like" means for clutter."""
    return float(max(t.rcs_dbsm for t in layout.types))
