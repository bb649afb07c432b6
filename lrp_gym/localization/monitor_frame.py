"""What one frame shows the reflector monitor, and how its returns are associated with the
mapped reflectors (:mod:`lrp_gym.localization.reflector_monitor`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lrp_gym.radar.detections import Detections


@dataclass(frozen=True)
class MonitorFrame:
    """What one converged frame shows the monitor (``ReflectorMonitor.observe``).

    Attributes
    ----------
    judged : ndarray (M,) of bool
        The reflectors this frame judges (visible, resolvable, not hidden by a much stronger
        return: :func:`masked_by_stronger`).
    residual_m : ndarray (M,)
        Nearest reflector-like distance minus each one's predicted distance (inf without any).
    bearing : ndarray (M, 2), optional
        Horizontal unit vectors from the estimated radar position to the reflectors; without
        them the displacement test does not see the frame.
    predicted_m : ndarray (M,), optional
        The reflectors' predicted distances.
    distances_m : ndarray (Z,)
        Every reflector-like distance of the frame, all types.
    velocities_mps : ndarray (Z,), optional
        Their radial velocities (None: the source measures none).
    velocity_xy : ndarray (2,), optional
        The robot's velocity over the floor: wheel speed along the estimated heading (None:
        no speed given).
    expected_velocity_mps : ndarray (M,), optional
        Each reflector's radial velocity predicted from the estimate and ``velocity_xy``
        (a static point's: ``-bearing @ velocity_xy``).
    parity_residual_m : ndarray (M,), optional
        The residuals the parity test takes: of the nearest return whose radial velocity fits
        the reflector's (the nearest one if none does); None: ``residual_m``.
    """

    judged: np.ndarray
    residual_m: np.ndarray
    bearing: np.ndarray | None = None
    predicted_m: np.ndarray | None = None
    distances_m: np.ndarray = field(default_factory=lambda: np.zeros(0))
    velocities_mps: np.ndarray | None = None
    velocity_xy: np.ndarray | None = None
    expected_velocity_mps: np.ndarray | None = None
    parity_residual_m: np.ndarray | None = None


def nearest_residuals(predicted: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Per reflector, the nearest of the reflector-like measured distances ``z`` minus the
    predicted one (inf without any). Distances of every type count: a weak return's RCS
    estimate scatters, and the tracker may give a small reflector's return to another type."""
    if len(z) == 0:
        return np.full(len(predicted), np.inf)
    diff = z[None, :] - predicted[:, None]
    return diff[np.arange(len(predicted)), np.argmin(np.abs(diff), axis=1)]


def doppler_residuals(
    predicted: np.ndarray,
    z: np.ndarray,
    velocities_mps: np.ndarray,
    expected_mps: np.ndarray,
    tolerance_mps: float,
) -> np.ndarray:
    """Per reflector, the residual of the nearest return whose radial velocity is within
    ``tolerance_mps`` of the reflector's predicted one ``expected_mps``; the nearest return's
    if none is (``z`` not empty)."""
    diff = z[None, :] - predicted[:, None]
    fits = np.abs(velocities_mps[None, :] - expected_mps[:, None]) <= tolerance_mps
    cost = np.where(fits, np.abs(diff), np.inf)
    rows = np.arange(len(predicted))
    best = np.argmin(cost, axis=1)
    pick = np.where(np.isfinite(cost[rows, best]), best, np.argmin(np.abs(diff), axis=1))
    return diff[rows, pick]


def masked_by_stronger(
    predicted: np.ndarray,
    expected_rcs_dbsm: np.ndarray,
    detections: Detections,
    gate_m: float,
    window_m: float,
    excess_db: float,
) -> np.ndarray:
    """Boolean (M,): a detection (of any kind) between ``gate_m`` and ``window_m`` from the
    reflector's predicted distance whose RCS exceeds the reflector's expected one
    (``expected_rcs_dbsm``, its pattern at this aspect) by ``excess_db``.

    A strong scatterer a few range cells from a weak reflector hides it: its skirt and its
    share of the CFAR's training cells raise the threshold there, and the peak search keeps the
    stronger maximum. Such a frame cannot tell a missing reflector from a masked one. Returns
    within the gate are the reflector's own (or answer for it): they never mask it.
    """
    dr = np.abs(detections.range_m[None, :] - predicted[:, None])
    strong = detections.rcs_dbsm[None, :] >= expected_rcs_dbsm[:, None] + excess_db
    return np.any(strong & (dr > gate_m) & (dr <= window_m), axis=1)
