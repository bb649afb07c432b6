"""Has one reflector moved? A likelihood-ratio test over a grid of displacements, in which
every return near the reflector's distance is a candidate for its own.

A reflector moved by ``d`` (horizontally) answers, seen from the estimated pose, at its
predicted distance plus ``u . d`` (``u``: the horizontal part of the unit vector from the
radar to it), give or take the radar's range noise ``s``. The nearest return to the predicted
distance is often not its own: the room's structure (ceiling, walls, edges, corners), ghosts
and clutter put about three reflector-like returns per metre around it, so the nearest-return
residual of a quarter-metre move is another return's in about a third of the frames (measured
on the patrol). So the test does not pick one return. In each frame, for every hypothesis
``d`` on a grid (radius ``max_shift_m``), the likelihood of the frame's returns near the
reflector is that of probabilistic data association with one target:

    p(returns | d) ~ (1 - P_D) + P_D * sum_z N(z - predicted; u . d, s^2) / lambda

(``P_D``: the reflector's detection probability; ``lambda``: the density per metre of the
other returns). The log-likelihoods add over the frames (with forgetting), and the statistic
``T_j = 2 (max_d L_j(d) - L_j(0))`` is the generalised likelihood ratio of "moved" against
"in place". A fixed move adds up at one grid cell, frame after frame, as the lines of sight
turn; the other returns land at cells that change with the robot's pose and spread out. As
with the parity test (:mod:`lrp_gym.localization.displacement_test`), the reflector is named
only if its statistic is high and ahead of every other reflector's (a moved reflector pulls
the estimate, so some of its residual shows at the others).

With a radial velocity per return (``doppler_std_mps`` > 0 and the robot's wheel speed), each
candidate's range density is multiplied by the density of its radial velocity under the
reflector's own line of sight over that of a static scatterer anywhere (the model of
:func:`~lrp_gym.localization.likelihood_terms.clutter_velocity_density`): the structure
returns that crowd a reflector's distance lie in other directions (ceiling, wall feet,
corners), so at driving speed they move at other radial velocities. The velocity a reflector
is predicted to have is that of its mapped position: a move of a few decimetres turns the line
of sight by a few degrees, a change far inside the velocity noise.

The residuals are taken from the estimate as it is (no position error removed): correcting
each frame with the position the other reflectors' returns imply took their wrong
associations in (docs/robustness.md). So a biased estimate (wheel slip: 5-10 cm behind) looks
like moved reflectors to this test; the monitor asks the parity test, which projects the
position error out, to confirm a name (``displacement_confirm_chi2``).
"""

from __future__ import annotations

import numpy as np

from lrp_gym.localization.displacement_test import leading_reflector
from lrp_gym.localization.likelihood_terms import (
    clutter_velocity_density,
    velocity_density_coefficients,
)

_SQRT_2PI = float(np.sqrt(2.0 * np.pi))


def displacement_grid(max_shift_m: float, step_m: float) -> np.ndarray:
    """Horizontal displacements (G, 2) on a square lattice of ``step_m`` within a disc of
    radius ``max_shift_m``, zero included."""
    n = int(np.floor(max_shift_m / step_m + 1e-9))
    g = step_m * np.arange(-n, n + 1)
    gx, gy = np.meshgrid(g, g)
    inside = gx**2 + gy**2 <= max_shift_m**2 + 1e-12
    return np.column_stack([gx[inside], gy[inside]])


class DisplacementGlrt:
    """Per-reflector log-likelihood of each candidate displacement, summed over the frames.

    Parameters
    ----------
    n_reflectors : int
        Mapped reflectors M.
    std_m : float
        Std ``s`` of a reflector's measured distance about the one a hypothesis predicts (the
        radar's range noise and the estimate's error).
    max_shift_m : float
        Largest move the test fits (farther moves leave the reflector's returns out of every
        gate: the monitor's miss count names them).
    detection_probability : float
        ``P_D``: probability that the reflector's own return is among the frame's distances.
    clutter_per_m : float
        ``lambda``: density of the other reflector-like distances around a reflector's, per
        metre of range.
    window_frames : int
        Exponential forgetting over about this many frames (those with three or more judged
        reflectors), so that a reflector moved mid-episode is seen as it is now.
    step_m : float
        Grid spacing of the hypotheses.
    doppler_std_mps : float
        Std of a reflector's measured radial velocity about its predicted one; 0 weighs the
        distances only.
    doppler_outlier_probability : float
        Probability that a return's velocity is unrelated to its own (a wrong Doppler peak),
        uniform over the radar's unambiguous interval.
    max_velocity_mps : float
        The radar's unambiguous radial velocity.

    Attributes
    ----------
    offsets_m : ndarray (G, 2)
        The hypotheses; ``offsets_m[zero_index]`` is no move.
    log_lr : ndarray (M, G)
        Summed log-likelihood of each hypothesis per reflector (up to a constant per frame).
    """

    def __init__(
        self,
        n_reflectors: int,
        std_m: float,
        max_shift_m: float,
        detection_probability: float,
        clutter_per_m: float,
        window_frames: int,
        step_m: float = 0.025,
        doppler_std_mps: float = 0.0,
        doppler_outlier_probability: float = 0.1,
        max_velocity_mps: float = 5.0,
    ) -> None:
        self.std_m = float(std_m)
        self.doppler_std_mps = float(doppler_std_mps)
        self.doppler_outlier_probability = float(doppler_outlier_probability)
        self.velocity_uniform = 0.5 / float(max_velocity_mps)
        self.detection_probability = float(detection_probability)
        self.clutter_per_m = float(clutter_per_m)
        self.keep = 1.0 - 1.0 / float(window_frames)
        self.offsets_m = displacement_grid(max_shift_m, step_m)
        self.zero_index = int(np.argmin(np.hypot(*self.offsets_m.T)))
        # Distances farther than this from a reflector's prediction fit no hypothesis.
        self.reach_m = float(max_shift_m) + 5.0 * self.std_m
        self.log_lr = np.zeros((n_reflectors, len(self.offsets_m)))

    def reset(self) -> None:
        self.log_lr[:] = 0.0

    def add(
        self,
        judged: np.ndarray,
        predicted_m: np.ndarray,
        distances_m: np.ndarray,
        bearing: np.ndarray,
        velocities_mps: np.ndarray | None = None,
        velocity_xy: np.ndarray | None = None,
        expected_velocity_mps: np.ndarray | None = None,
    ) -> None:
        """Add one frame: ``judged`` (M,) bool, ``predicted_m`` (M,) the reflectors'
        distances from the estimate, ``distances_m`` (Z,) every reflector-like distance of
        the frame (all types), ``bearing`` (M, 2) the horizontal unit vectors from the radar
        to the reflectors (d distance / d reflector xy). With ``velocities_mps`` (Z,), the
        distances' radial velocities, and ``velocity_xy`` (2,), the robot's estimated
        velocity over the floor, the Doppler weighs the candidates too;
        ``expected_velocity_mps`` (M,), the reflectors' predicted radial velocities, if the
        caller has them (else ``-bearing @ velocity_xy``)."""
        idx = np.flatnonzero(judged)
        if len(idx) < 3:  # the others do not vouch for the pose
            return
        self.log_lr *= self.keep
        diff = np.asarray(distances_m, dtype=float)[None, :] - predicted_m[idx, None]
        near = np.abs(diff) <= self.reach_m
        cols = near.any(axis=0)
        diff = np.where(near, diff, np.inf)[:, cols]  # (J, Z')
        weight = None
        if self.doppler_std_mps > 0.0 and velocities_mps is not None and velocity_xy is not None:
            # A static point's radial velocity is -v . u (u: unit vector from the radar).
            if expected_velocity_mps is None:
                expected_velocity_mps = -bearing @ np.asarray(velocity_xy, dtype=float)
            expected = np.asarray(expected_velocity_mps, dtype=float)[idx]
            measured = np.asarray(velocities_mps, dtype=float)[cols]
            weight = self._doppler_ratio(measured, expected, velocity_xy)
        shift = bearing[idx] @ self.offsets_m.T  # (J, G): u . d
        self.log_lr[idx] += self._terms(diff, shift, weight)

    def _doppler_ratio(
        self, measured: np.ndarray, expected: np.ndarray, velocity_xy: np.ndarray
    ) -> np.ndarray:
        """(J, Z): density of each measured radial velocity ``measured`` (Z,) as the return of
        a reflector expected at ``expected`` (J,) over its density as a static scatterer's at
        this speed (the localiser's clutter model)."""
        s, u = self.doppler_std_mps, self.velocity_uniform
        a, b, c = velocity_density_coefficients(s, self.doppler_outlier_probability, u)
        dv = measured[None, :] - expected[:, None]
        own = a * np.exp(c * dv * dv) + b
        speed = float(np.hypot(*velocity_xy))
        return own / clutter_velocity_density(speed, s, u, measured)[None, :]

    def _terms(
        self, diff: np.ndarray, shift: np.ndarray, weight: np.ndarray | None = None
    ) -> np.ndarray:
        """One frame's log-likelihood terms (J, G) of the hypotheses, up to a constant per
        reflector: ``diff`` (J, Z) candidates minus predicted distances, ``shift`` (J, G) the
        offsets ``u . d`` the hypotheses predict, ``weight`` (J, Z) each candidate's Doppler
        density ratio (None: 1)."""
        z = (diff[:, None, :] - shift[:, :, None]) / self.std_m
        g = np.exp(-0.5 * z * z)
        if weight is not None:
            g *= weight[:, None, :]
        density = g.sum(axis=2) / (_SQRT_2PI * self.std_m)
        p_d = self.detection_probability
        return np.log((1.0 - p_d) + p_d * density / self.clutter_per_m)

    @property
    def statistic(self) -> np.ndarray:
        """``T_j`` (M,): twice the log-likelihood ratio of the best displacement against
        none."""
        return 2.0 * (self.log_lr.max(axis=1) - self.log_lr[:, self.zero_index])

    @property
    def displacement_m(self) -> np.ndarray:
        """The most likely horizontal displacement (M, 2) of each reflector, in m."""
        return self.offsets_m[np.argmax(self.log_lr, axis=1)]

    def leader(self, chi2: float, lead: float, statistic: np.ndarray | None = None) -> int | None:
        """The reflector whose statistic is at least ``chi2`` and ahead of every other one's
        by ``lead`` (None if there is none; ``statistic``: :attr:`statistic` if computed)."""
        return leading_reflector(self.statistic if statistic is None else statistic, chi2, lead)
