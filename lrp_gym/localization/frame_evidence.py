"""How much new evidence a frame brings: the likelihood's exponent from the robot's motion.

At one spot the radar sees the same room: a static scatterer's return lands at the same
distance every frame, and so does a reflector's error from multipath or from a scatterer
merged into its range cell. A robot that stands, turns on the spot (the radar, on its axis,
sees no change) or creeps would count that evidence again each frame, and under unmapped
clutter a wrong pose that explains the scatterers wins by repetition. Measured on the signal
chain (``docs/trust.md``, session 16): a reflector's range errors two frames apart correlate
about 0.6 at the same spot (thermal noise and millimetres of motion, which turn the carrier
phases, take the rest) and 0.0-0.2 after 6-10 cm (``docs/scripts/frame_correlation.py``).

Model: the evidence is a stationary process along the path with correlation
``rho(d) = exp(-d / L)``. For such a process the effective number of independent samples among
n frames a step ``d`` apart is ``n (1 - rho) / (1 + rho)``, so each frame's log-likelihood is
scaled by ``(1 - rho) / (1 + rho)`` on top of the constant tempering: 1 for the first frame
(and after a long way), 0 for a frame at the same spot as the last one. The correlation at the
same spot is taken as 1 (a static scatterer's return repeats exactly there): with the 0.6 of
the reflectors' own errors (a frame there still weighing 0.25) the model bought nothing under
clutter (docs/trust.md).
"""

from __future__ import annotations

import math


def independence_weight(moved_m: float, correlation_m: float | None) -> float:
    """``(1 - rho) / (1 + rho)`` with ``rho = exp(-moved_m / correlation_m)``; 1 if
    ``correlation_m`` is None (frames treated as independent)."""
    if correlation_m is None or not math.isfinite(moved_m):
        return 1.0
    rho = math.exp(-max(moved_m, 0.0) / correlation_m)
    return (1.0 - rho) / (1.0 + rho)


class FrameEvidence:
    """The distance travelled since the last weighed frame, and that frame's exponent.

    Parameters
    ----------
    base_exponent : float
        The constant tempering (``likelihood_exponent``): the exponent of an independent frame.
    correlation_m : float or None
        ``L`` of the errors' correlation along the path (``likelihood_correlation_m``); None:
        every frame weighs ``base_exponent``.
    """

    def __init__(self, base_exponent: float, correlation_m: float | None) -> None:
        self.base_exponent = float(base_exponent)
        self.correlation_m = correlation_m
        self.moved_m = math.inf

    def reset(self) -> None:
        """A new start: the next frame is independent of everything weighed so far."""
        self.moved_m = math.inf

    def move(self, translation_m: float) -> None:
        """Add an odometry step's translation (m; its sign does not matter)."""
        self.moved_m += abs(float(translation_m))

    def independence(self) -> float:
        """The share of an independent frame that a frame weighed now counts for, without the
        constant tempering and without starting the distance anew (the lost test's weight)."""
        return independence_weight(self.moved_m, self.correlation_m)

    def restart(self) -> float:
        """:meth:`reset`, then :meth:`take`: the exponent of a new cloud's first frame."""
        self.reset()
        return self.take()

    def take(self) -> float:
        """The exponent of the frame weighed now; the distance counts from here again."""
        exponent = self.base_exponent * independence_weight(self.moved_m, self.correlation_m)
        self.moved_m = 0.0
        return exponent
