"""Pose estimates from weighted particles: circular statistics, best-k and cluster means."""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from lrp_gym.localization.particle_motion import wrap_fast


def circular_mean(angles_rad: np.ndarray, weights: np.ndarray | None = None) -> float:
    """Weighted mean direction in [-pi, pi): the angle of the mean unit vector."""
    w = np.ones_like(angles_rad) if weights is None else weights
    return float(np.arctan2(np.dot(w, np.sin(angles_rad)), np.dot(w, np.cos(angles_rad))))


def circular_variance_rad2(angles_rad: np.ndarray, weights: np.ndarray | None = None) -> float:
    """Heading variance ``-2 ln R`` in rad^2 (R = mean resultant length).

    It is the sigma^2 of the wrapped normal with that resultant length: equal to the ordinary
    variance for small spreads and growing without bound as the headings become uniform.
    The trigonometry runs in float32 (SIMD; R needs no more precision).
    """
    w = np.ones(len(angles_rad)) if weights is None else weights
    a32 = angles_rad.astype(np.float32)
    r = np.hypot(np.dot(w, np.sin(a32)), np.dot(w, np.cos(a32))) / float(np.sum(w))
    return float(-2.0 * np.log(min(max(r, 1e-300), 1.0)))


def weighted_pose_mean(particles: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Weighted mean pose (3,): arithmetic in x, y; circular in heading."""
    w = weights / np.sum(weights)
    return np.array([w @ particles[:, 0], w @ particles[:, 1], circular_mean(particles[:, 2], w)])


def pose_covariance(particles: np.ndarray, weights: np.ndarray, mean: np.ndarray) -> np.ndarray:
    """Weighted 3x3 covariance about ``mean`` (the estimate, so a biased estimate shows).

    Heading deviations are wrapped to [-pi, pi) for the cross terms; the heading variance
    itself is the circular ``-2 ln R`` (:func:`circular_variance_rad2`), which stays correct
    for headings spread around the circle.
    """
    w = weights / np.sum(weights)
    dx = particles[:, 0] - mean[0]
    dy = particles[:, 1] - mean[1]
    dth = wrap_fast(particles[:, 2] - mean[2])
    wdx = w * dx
    wdy = w * dy
    cov = np.empty((3, 3))
    cov[0, 0] = wdx @ dx
    cov[1, 1] = wdy @ dy
    cov[0, 1] = cov[1, 0] = wdx @ dy
    cov[0, 2] = cov[2, 0] = wdx @ dth
    cov[1, 2] = cov[2, 1] = wdy @ dth
    cov[2, 2] = circular_variance_rad2(particles[:, 2], w)
    return cov


def best_k_mean(
    particles: np.ndarray, weights: np.ndarray, k: int = 20, radius_m: float = 0.15
) -> np.ndarray:
    """The paper's estimate: weighted mean of the ``k`` heaviest particles within ``radius_m``
    of the heaviest one."""
    best = int(np.argmax(weights))
    d2 = (particles[:, 0] - particles[best, 0]) ** 2 + (particles[:, 1] - particles[best, 1]) ** 2
    near = np.flatnonzero(d2 <= radius_m**2)
    if len(near) > k:
        near = near[np.argpartition(weights[near], -k)[-k:]]
    w = weights[near]
    if not np.sum(w) > 0.0:
        w = np.ones(len(near))
    return weighted_pose_mean(particles[near], w)


def dominant_cluster(
    particles: np.ndarray,
    weights: np.ndarray,
    bin_m: float,
    size_xy_m: np.ndarray,
    min_bin_mass: float = 1e-3,
) -> tuple[np.ndarray, float]:
    """The heaviest cluster of particles: a boolean mask (N,) and its share of the weight
    (see :func:`clusters`)."""
    sel, masses = clusters(particles, weights, bin_m, size_xy_m, min_bin_mass)
    return sel, float(masses[0]) if len(masses) else 0.0


def clusters(
    particles: np.ndarray,
    weights: np.ndarray,
    bin_m: float,
    size_xy_m: np.ndarray,
    min_bin_mass: float = 1e-3,
) -> tuple[np.ndarray, np.ndarray]:
    """The modes of a particle set: the heaviest one's mask (N,) and every mode's share.

    Particles are binned on an (x, y) grid of ``bin_m``; bins holding at least
    ``min_bin_mass`` of the total weight and touching each other (8-connectivity) form a
    cluster; the cluster with the largest total weight wins. The mass threshold keeps a
    sprinkle of near-weightless particles (a uniform prior's remains, injected ones) from
    bridging separate modes into one. Heading is left out of the clustering (it would need
    wrap-around connectivity). With no bin above the threshold (a flat posterior) the mask
    selects every particle and no mode is returned. The shares (descending) are of the total
    weight, so they sum to less than 1 by the weight of the light bins.
    """
    labels, masses = cluster_labels(particles, weights, bin_m, size_xy_m, min_bin_mass)
    if len(masses) <= 1:
        return np.ones(len(particles), dtype=bool), np.zeros(0)
    best = int(np.argmax(masses[1:])) + 1
    return labels == best, -np.sort(-masses[1:])


def cluster_labels(
    particles: np.ndarray,
    weights: np.ndarray,
    bin_m: float,
    size_xy_m: np.ndarray,
    min_bin_mass: float = 1e-3,
) -> tuple[np.ndarray, np.ndarray]:
    """Mode label of every particle (0: in a light bin, 1..K: a mode) and the weight share of
    each label (K + 1,), labels as in :func:`clusters`."""
    n = np.maximum(np.ceil(np.asarray(size_xy_m, float) / bin_m).astype(int), 1) + 1
    # min/max instead of np.clip: same result, a fraction of the call overhead.
    ix = np.minimum(np.maximum((particles[:, 0] / bin_m).astype(np.int64), 0), n[0] - 1)
    iy = np.minimum(np.maximum((particles[:, 1] / bin_m).astype(np.int64), 0), n[1] - 1)
    flat = ix * n[1] + iy
    mass = np.bincount(flat, weights=weights, minlength=n[0] * n[1]).reshape(n)
    total = float(mass.sum())
    out = np.zeros(len(particles), dtype=np.int64)
    if not total > 0.0:
        return out, np.ones(1)
    heavy = mass >= min_bin_mass * total
    rows = np.flatnonzero(heavy.any(axis=1))
    if len(rows) == 0:
        return out, np.ones(1)
    cols = np.flatnonzero(heavy.any(axis=0))
    # Label only the bounding box of the heavy bins (a converged set covers a few bins).
    r0, r1, c0, c1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
    labels, _ = ndimage.label(heavy[r0:r1, c0:c1], structure=np.ones((3, 3), dtype=bool))
    inside = (ix >= r0) & (ix < r1) & (iy >= c0) & (iy < c1)
    out[inside] = labels[ix[inside] - r0, iy[inside] - c0]
    return out, np.bincount(out, weights=weights, minlength=labels.max() + 1) / total


def cluster_mean(
    particles: np.ndarray, weights: np.ndarray, bin_m: float, size_xy_m: np.ndarray
) -> np.ndarray:
    """Weighted mean of the heaviest cluster of particles (:func:`dominant_cluster`); the
    heading is averaged circularly within it."""
    sel, _ = dominant_cluster(particles, weights, bin_m, size_xy_m)
    w = weights[sel]
    if not np.sum(w) > 0.0:
        w = np.ones(int(sel.sum()))
    return weighted_pose_mean(particles[sel], w)
