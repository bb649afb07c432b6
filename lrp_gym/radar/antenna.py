"""Elevation pattern of a radar antenna facing the ceiling (optional; default omnidirectional).

A broad cone about the zenith keeps the reflectors (all above the radar) in view and turns
down the horizontal returns of the walls, which are the strongest clutter in a room. The
pattern is rotationally symmetric about the vertical: the one-way power gain relative to
boresight is a Gaussian in the zenith angle, ``10^(-0.3 (theta / theta_3dB)^2)``, never below
a floor that stands for the side and back lobes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ZenithPattern:
    """One-way power pattern of an upward-facing antenna.

    Parameters
    ----------
    half_power_deg : float
        Zenith angle at which the gain is 3 dB below boresight.
    floor_db : float
        Lowest gain relative to boresight (side/back lobes), in dB.
    """

    half_power_deg: float
    floor_db: float = -20.0

    def gain(self, cos_zenith: np.ndarray) -> np.ndarray:
        """Power gain (0..1) for the cosine of the zenith angle of a direction."""
        theta = np.degrees(np.arccos(np.clip(cos_zenith, -1.0, 1.0)))
        g = 10.0 ** (-0.3 * (theta / self.half_power_deg) ** 2)
        return np.maximum(g, 10.0 ** (self.floor_db / 10.0))
