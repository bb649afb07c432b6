"""KLD sampling (Fox 2003): how many particles a posterior spread over ``k`` bins needs.

AMCL computes the count vectorised rather than incrementally: the ``k`` occupied bins are
counted on a systematic resample of the current size ``N``, and the new size is
``n_chi(k)`` clamped to ``[min_particles, max_particles]``. Because ``k`` can only grow with
the sample size, this never asks for fewer particles than Fox's incremental rule on the same
draw would when the population shrinks; it adapts one resampling step later when it grows.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy.stats import norm

from lrp_gym.config import LocalizationConfig


@lru_cache(maxsize=16)
def _normal_quantile(p: float) -> float:
    return float(norm.ppf(p))  # ~50 us per scipy call: computed once per quantile


def kld_particle_count(k: int, epsilon: float, quantile: float) -> int:
    """Particles needed so that the KL divergence stays below ``epsilon`` with prob. ``quantile``.

    Wilson-Hilferty approximation of the chi-square quantile with ``k - 1`` degrees of freedom:
    ``n = (k-1)/(2 eps) (1 - 2/(9(k-1)) + sqrt(2/(9(k-1))) z)^3``, with ``z`` the standard
    normal *quantile* of ``quantile`` (nav2's AMCL passes the probability itself, a known bug).
    Returns 0 for ``k <= 1`` (the caller clamps to its minimum).
    """
    if k <= 1:
        return 0
    z = _normal_quantile(float(quantile))
    a = 2.0 / (9.0 * (k - 1))
    return int(np.ceil((k - 1) / (2.0 * epsilon) * (1.0 - a + np.sqrt(a) * z) ** 3))


class KldBinner:
    """Counts occupied (x, y, theta) bins of a particle set in O(N).

    A reusable flag array over the room's bins replaces ``np.unique`` (a sort).

    Parameters
    ----------
    size_xy_m : (2,) room extent
    bin_m, bin_rad : bin sizes
    """

    def __init__(self, size_xy_m: np.ndarray, bin_m: float, bin_rad: float) -> None:
        self.bin_m = float(bin_m)
        self.n_xy = np.maximum(np.ceil(np.asarray(size_xy_m, float) / bin_m).astype(int), 1) + 1
        self.n_th = max(int(np.ceil(2.0 * np.pi / bin_rad)), 1)
        self.bin_rad = 2.0 * np.pi / self.n_th
        self._flags = np.zeros(int(self.n_xy[0] * self.n_xy[1] * self.n_th), dtype=bool)

    def keys(self, particles: np.ndarray) -> np.ndarray:
        """Flat bin index of each particle (N,)."""
        ix = np.clip((particles[:, 0] / self.bin_m).astype(np.int64), 0, self.n_xy[0] - 1)
        iy = np.clip((particles[:, 1] / self.bin_m).astype(np.int64), 0, self.n_xy[1] - 1)
        it = np.clip(((particles[:, 2] + np.pi) / self.bin_rad).astype(np.int64), 0, self.n_th - 1)
        return (ix * self.n_xy[1] + iy) * self.n_th + it

    def count(self, particles: np.ndarray, index: np.ndarray | None = None) -> int:
        """Number of distinct bins the particles (or ``particles[index]``) occupy."""
        keys = self.keys(particles)
        if index is not None:
            keys = keys[index]
        self._flags[keys] = True
        k = int(np.count_nonzero(self._flags))
        self._flags[keys] = False
        return k


def clamped_particle_count(cfg: LocalizationConfig, k_bins: int) -> int:
    """:func:`kld_particle_count` with ``cfg``'s error and quantile, clamped to
    ``[cfg.min_particles, cfg.max_particles]``."""
    n = kld_particle_count(k_bins, cfg.kld_error, cfg.kld_quantile)
    return min(max(n, cfg.min_particles), cfg.max_particles)


def augmented_particle_count(cfg: LocalizationConfig, k_bins: int, p_random: float) -> int:
    """:func:`clamped_particle_count` for a cloud into which a share ``p_random`` of random
    particles is injected. Fox's incremental KLD draws from the augmented mixture, so the
    random particles (almost each in a bin of its own) raise ``k`` too:
    ``n = n_chi(k + p_random n)``, solved by fixed-point iteration."""
    n = clamped_particle_count(cfg, k_bins)
    if p_random > 0.0:
        for _ in range(32):
            n_next = clamped_particle_count(cfg, k_bins + int(p_random * n))
            if n_next <= n:
                break
            n = n_next
    return n
