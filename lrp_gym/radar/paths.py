"""Propagation paths of one radar frame: the :class:`Paths` record and the path kinds.

The channel (:mod:`lrp_gym.radar.channel`) produces them; the front end and the fast
detection model consume them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

KIND_DIRECT = 0
KIND_REFLECTOR_MULTIPATH = 1
KIND_SURFACE = 2
KIND_OBSTACLE_FACE = 3
KIND_SCATTERER = 4
KIND_NAMES = ("direct", "reflector_multipath", "surface", "obstacle_face", "scatterer")


def _f(a=()) -> np.ndarray:
    return np.asarray(a, dtype=float).reshape(-1)


@dataclass(frozen=True)
class Paths:
    """Propagation paths of one radar frame (all arrays of shape (P,)).

    Attributes
    ----------
    range_m : ndarray
        Half the round-trip path length.
    velocity_mps : ndarray
        Rate of change of ``range_m`` (positive when receding).
    power_w : ndarray
        Received power at the antenna port.
    phase_rad : ndarray
        Carrier phase of the return, ``4 pi range / lambda + pi * bounces``.
    reflector_index : ndarray of int
        Index into the layout for reflector paths, ``-1`` for surfaces and ``-2`` for extra
        scatterers.
    order : ndarray of int
        Number of surface bounces on the path.
    kind : ndarray of int
        One of the ``KIND_*`` codes (see :data:`KIND_NAMES`).
    """

    range_m: np.ndarray = field(default_factory=_f)
    velocity_mps: np.ndarray = field(default_factory=_f)
    power_w: np.ndarray = field(default_factory=_f)
    phase_rad: np.ndarray = field(default_factory=_f)
    reflector_index: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    order: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    kind: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    def __len__(self) -> int:
        return len(self.range_m)

    def select(self, mask_or_index) -> Paths:
        """A subset of the paths."""
        return Paths(*(getattr(self, k)[mask_or_index] for k in _FIELDS))

    @staticmethod
    def concatenate(parts: list[Paths]) -> Paths:
        if not parts:
            return Paths()
        return Paths(*(np.concatenate([getattr(p, k) for p in parts]) for k in _FIELDS))


_FIELDS = ("range_m", "velocity_mps", "power_w", "phase_rad", "reflector_index", "order", "kind")
