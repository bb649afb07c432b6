"""Wheel-slip-aware motion noise: inflate the odometry noise while odometry and radar disagree.

AMCL's motion model trusts the odometry within fixed standard deviations. On a slippery floor
(or with a worn wheel) the reported distance and turn are biased by more than that, frame
after frame: the cloud is pushed away from the truth faster than the measurements pull it
back, and the estimate lags. The radar tells: the converged estimate then sits, frame after
frame, further from where the odometry alone moved the previous estimate than the motion
noise explains. :class:`SlipMonitor` keeps an exponentially weighted mean of that
normalised correction squared (a normalised innovation, about 1 or less while the odometry is
as good as the model says) and scales the motion noise by its square root, from 1 up to
``max_inflation``; when the two agree again the scale decays back to 1.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lrp_gym.config.localization import LocalizationConfig
from lrp_gym.world.robot import OdometryNoise, apply_odometry, wrap_angle

#: Weight of the newest frame in the mean (about five frames of memory).
_ALPHA = 0.2


@dataclass
class SlipMonitor:
    """One robot's motion-noise inflation (reset per run).

    Parameters
    ----------
    base : OdometryNoise
        The localiser's motion noise without slip.
    max_inflation : float
        Largest factor on the standard deviations.
    """

    base: OdometryNoise
    max_inflation: float
    scale: float = field(default=1.0, init=False)

    def __post_init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self.scale = 1.0
        self._mean_z2 = 0.0
        self._last_pose: np.ndarray | None = None

    def noise(self) -> OdometryNoise:
        """The motion noise to sample this frame with."""
        if self.scale == 1.0:
            return self.base
        s = self.scale
        b = self.base
        return OdometryNoise(
            b.sigma_turn_rad * s, b.sigma_distance_m * s, tuple(a * s for a in b.alphas)
        )

    def update(self, odometry: np.ndarray, pose: np.ndarray, converged: bool) -> None:
        """Compare this frame's estimate ``pose`` with the previous one moved by ``odometry``
        (only when both are converged) and set the next frame's scale."""
        last, self._last_pose = self._last_pose, (np.asarray(pose, float) if converged else None)
        if last is None or not converged:
            return
        odometry = np.asarray(odometry, dtype=float)
        predicted = apply_odometry(last, odometry)
        std = self.base.std(odometry)
        # The position's spread: the distance's noise along, the first turn's across.
        sigma_xy = float(np.hypot(std[1], abs(odometry[1]) * std[0]))
        sigma_th = float(np.hypot(std[0], std[2]))
        dxy = float(np.hypot(*(pose[:2] - predicted[:2])))
        dth = abs(float(wrap_angle(pose[2] - predicted[2])))
        z2 = max((dxy / sigma_xy) ** 2, (dth / sigma_th) ** 2)
        self._mean_z2 += _ALPHA * (z2 - self._mean_z2)
        self.scale = float(np.clip(np.sqrt(self._mean_z2), 1.0, self.max_inflation))


def slip_monitor(noise: OdometryNoise, cfg: LocalizationConfig) -> SlipMonitor | None:
    """A fresh monitor for a localiser with motion noise ``noise``, if ``cfg`` asks for one."""
    return SlipMonitor(noise, cfg.slip_max_inflation) if cfg.slip_adaptive else None
