"""Has one reflector moved? A parity-space test on the range residuals, pose error removed.

In a frame, the residuals ``r`` (measured minus predicted distance, from the estimated pose)
of the judged reflectors mix two things: the estimate's position error, common to all of
them through the geometry ``H`` (rows: minus each reflector's unit bearing), and a moved
reflector ``j``'s own offset ``u_j . d_j`` (``d_j``: its horizontal displacement). The
projection ``P = I - H (H^T H)^-1 H^T`` onto the residual space orthogonal to ``H`` (the
parity space of receiver autonomous integrity monitoring in GNSS) removes any position error
to first order, so what is left is measurement noise and faults. With at least three judged
reflectors the space is not empty.

A displacement is fixed while the robot moves, so the frames add up: for the hypothesis that
reflector ``j`` moved, the least-squares fit of ``d_j`` over the frames has normal equations
``A_j = sum P_jj u_j u_j^T / s^2``, ``b_j = sum u_j (P r)_j / s^2``, and its statistic
``T_j = b_j^T A_j^-1 b_j`` is chi-square with 2 degrees of freedom if nothing moved (white
noise of std ``s``). A move across every line of sight does not show in any one frame but
does once the robot has seen the reflector from a few directions. One fault spreads into the
other reflectors' statistics (they share the frames' projections), so the test names the
reflector whose ``T`` is both high and clearly ahead of every other's.

Only residuals within ``gate_m`` enter: farther returns are another reflector's, a ghost's
or clutter (the monitor's miss count covers reflectors moved beyond the gate).
"""

from __future__ import annotations

import numpy as np

# Keeps A_j invertible before the reflector has been seen from two directions (1/m^2; the
# entries grow by about 1 / s^2 = 1100 per frame).
_RIDGE = 1e-3


class DisplacementTest:
    """Per-reflector evidence that it moved, from the parity residuals of the frames.

    Parameters
    ----------
    n_reflectors : int
        Mapped reflectors M.
    std_m : float
        Std of a measured distance, without the pose error (the radar's range noise).
    gate_m : float
        Residuals beyond this do not enter (association).
    window_frames : int
        Exponential forgetting over about this many frames (with three or more reflectors
        judged), so that a reflector moved mid-episode (or put back) is seen as it is now.

    Attributes
    ----------
    normal_m2 : ndarray (M, 2, 2)
        ``A_j``, in 1/m^2.
    moment : ndarray (M, 2)
        ``b_j``, in 1/m.
    """

    def __init__(self, n_reflectors: int, std_m: float, gate_m: float, window_frames: int):
        self.std_m = float(std_m)
        self.gate_m = float(gate_m)
        self.keep = 1.0 - 1.0 / float(window_frames)
        self.normal_m2 = np.zeros((n_reflectors, 2, 2))
        self.moment = np.zeros((n_reflectors, 2))

    def reset(self) -> None:
        self.normal_m2[:] = 0.0
        self.moment[:] = 0.0

    def add(self, judged: np.ndarray, residual_m: np.ndarray, bearing: np.ndarray) -> None:
        """Add one frame: ``judged`` (M,) bool, ``residual_m`` (M,) measured minus predicted
        distances, ``bearing`` (M, 2) d(distance)/d(reflector xy), the horizontal part of
        the unit vector from the radar to each reflector."""
        idx = np.flatnonzero(judged & (np.abs(residual_m) <= self.gate_m))
        if len(idx) < 3:  # two ranges fix the position: nothing left to check
            return
        u = bearing[idx]
        # Projection onto the residuals no position error can produce (H = -u).
        gram = u.T @ u
        if abs(np.linalg.det(gram)) < 1e-9:  # reflectors in one line: position not fixed
            return
        proj = np.eye(len(idx)) - u @ np.linalg.solve(gram, u.T)
        parity = proj @ residual_m[idx]
        w = 1.0 / self.std_m**2
        # Every reflector forgets, judged in this frame or not: one left out (a suspect, or
        # out of view) fades rather than keeping an old verdict.
        self.normal_m2 *= self.keep
        self.moment *= self.keep
        self.normal_m2[idx] += w * np.diag(proj)[:, None, None] * u[:, :, None] * u[:, None, :]
        self.moment[idx] += w * parity[:, None] * u

    @property
    def statistic(self) -> np.ndarray:
        """``T_j`` (M,): chi-square (2 dof) of the fitted displacement of each reflector."""
        a = self.normal_m2 + _RIDGE * np.eye(2)
        return np.einsum(
            "mi,mi->m", self.moment, np.linalg.solve(a, self.moment[..., None])[..., 0]
        )

    @property
    def displacement_m(self) -> np.ndarray:
        """The fitted horizontal displacement (M, 2) of each reflector, in m."""
        a = self.normal_m2 + _RIDGE * np.eye(2)
        return np.linalg.solve(a, self.moment[..., None])[..., 0]

    def leader(self, chi2: float, lead: float, statistic: np.ndarray | None = None) -> int | None:
        """The reflector whose statistic is at least ``chi2`` and ahead of every other one's
        by ``lead`` (None if there is none; ``statistic``: :attr:`statistic` if computed)."""
        return leading_reflector(self.statistic if statistic is None else statistic, chi2, lead)


def leading_reflector(statistic: np.ndarray, chi2: float, lead: float) -> int | None:
    """Index of the largest ``statistic`` if it is at least ``chi2`` and exceeds every other
    one by ``lead``; else None (also with fewer than two reflectors)."""
    if len(statistic) < 2:
        return None
    order = np.argsort(statistic)
    j, second = int(order[-1]), float(statistic[order[-2]])
    return j if statistic[j] >= chi2 and statistic[j] - second >= lead else None
