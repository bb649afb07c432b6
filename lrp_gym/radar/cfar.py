"""2-D CFAR detectors (CA, SO, GO, OS) on a square-law range-Doppler power map.

Window around the cell under test: ``guard`` cells and, outside them, ``training`` cells on
each side along range (axis 0) and Doppler (axis 1). The range axis is padded by mirroring,
the Doppler axis wraps around (it is circular).

Thresholds follow from the design false-alarm probability for exponentially distributed
(square-law, complex Gaussian) noise:

- CA: ``T = alpha / N * sum``, ``alpha = N (Pfa^(-1/N) - 1)``.
- SO / GO: the training ring is split into the half before and the half after the cell in
  range (n cells each; the cell's own range row is not used); ``T = alpha * min|max(sums)``
  with ``Pfa_SO = 2 sum_k C(n-1+k, k) (2 + alpha)^-(n+k)`` and
  ``Pfa_GO = 2 (1 + alpha)^-n - Pfa_SO``.
- OS: ``T = alpha * X_(k)`` (k-th smallest of the N training cells),
  ``Pfa_OS = prod_{i<k} (N - i) / (N - i + alpha)``.
SO, GO and OS factors are solved numerically (brentq on log Pfa) and cached.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np
from scipy.ndimage import rank_filter
from scipy.optimize import brentq
from scipy.special import gammaln

METHODS = ("CA", "SO", "GO", "OS")


def log_pfa_so(alpha: float, n: int) -> float:
    k = np.arange(n)
    terms = gammaln(n + k) - gammaln(k + 1) - gammaln(n) - (n + k) * np.log(2.0 + alpha)
    return float(np.log(2.0) + np.logaddexp.reduce(terms))


def log_pfa_go(alpha: float, n: int) -> float:
    so = math.exp(log_pfa_so(alpha, n))
    return math.log(max(2.0 * (1.0 + alpha) ** (-n) - so, 1e-300))


def log_pfa_os(alpha: float, n: int, k: int) -> float:
    i = np.arange(k)
    return float(np.sum(np.log(n - i) - np.log(n - i + alpha)))


@lru_cache(maxsize=64)
def threshold_factor(method: str, pfa: float, n_total: int, n_half: int, rank: int) -> float:
    """CFAR factor ``alpha`` for a design ``pfa`` (see the module docstring)."""
    if method == "CA":
        return n_total * (pfa ** (-1.0 / n_total) - 1.0)
    target = math.log(pfa)
    if method == "SO":
        f = lambda a: log_pfa_so(a, n_half) - target  # noqa: E731
    elif method == "GO":
        f = lambda a: log_pfa_go(a, n_half) - target  # noqa: E731
    elif method == "OS":
        f = lambda a: log_pfa_os(a, n_total, rank) - target  # noqa: E731
    else:
        raise ValueError(f"unknown CFAR method {method!r}; expected one of {METHODS}")
    hi = 1.0
    while f(hi) > 0:
        hi *= 2.0
    return float(brentq(f, 1e-12, hi, xtol=1e-12, rtol=1e-12))


@dataclass(frozen=True)
class Cfar2D:
    """A 2-D CFAR detector.

    Parameters
    ----------
    method : {"CA", "SO", "GO", "OS"}
    guard : (int, int)
        Guard cells on each side along (range, Doppler).
    training : (int, int)
        Training cells beyond the guard cells on each side along (range, Doppler).
    pfa : float
        Design false-alarm probability per cell.
    os_rank : float
        OS only: rank as a fraction of the number of training cells.
    """

    method: str = "CA"
    guard: tuple[int, int] = (2, 1)
    training: tuple[int, int] = (8, 3)
    pfa: float = 1e-6
    os_rank: float = 0.75

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ValueError(f"unknown CFAR method {self.method!r}; expected one of {METHODS}")
        object.__setattr__(self, "guard", tuple(int(g) for g in self.guard))
        object.__setattr__(self, "training", tuple(int(t) for t in self.training))
        if self.method in ("SO", "GO") and self.training[0] < 1:
            raise ValueError("SO/GO CFAR needs training cells along range")

    @property
    def half_window(self) -> tuple[int, int]:
        return (self.guard[0] + self.training[0], self.guard[1] + self.training[1])

    @property
    def n_training(self) -> int:
        """Training cells in the ring around the cell under test."""
        (g0, g1), (h0, h1) = self.guard, self.half_window
        return (2 * h0 + 1) * (2 * h1 + 1) - (2 * g0 + 1) * (2 * g1 + 1)

    @property
    def n_half(self) -> int:
        """Training cells in each range half (SO/GO)."""
        (g0, g1), (h0, h1) = self.guard, self.half_window
        return h0 * (2 * h1 + 1) - g0 * (2 * g1 + 1)

    @property
    def rank(self) -> int:
        """OS: 1-based rank of the order statistic."""
        return int(min(max(math.ceil(self.os_rank * self.n_training), 1), self.n_training))

    @cached_property
    def alpha(self) -> float:
        return threshold_factor(self.method, self.pfa, self.n_training, self.n_half, self.rank)

    def _pad(self, power: np.ndarray) -> np.ndarray:
        h0, h1 = self.half_window
        p = np.pad(power, ((h0, h0), (0, 0)), mode="symmetric")
        return np.pad(p, ((0, 0), (h1, h1)), mode="wrap")

    def threshold(self, power: np.ndarray) -> np.ndarray:
        """Detection threshold for every cell of ``power`` (range x Doppler)."""
        power = np.asarray(power, dtype=np.float64)
        nr, nd = power.shape
        h0, h1 = self.half_window
        g0, g1 = self.guard
        padded = self._pad(power)
        if self.method == "OS":
            foot = np.ones((2 * h0 + 1, 2 * h1 + 1), bool)
            foot[h0 - g0 : h0 + g0 + 1, h1 - g1 : h1 + g1 + 1] = False
            x = rank_filter(padded, rank=self.rank - 1, footprint=foot, mode="constant")
            return self.alpha * x[h0 : h0 + nr, h1 : h1 + nd]
        sat = np.zeros((padded.shape[0] + 1, padded.shape[1] + 1))
        np.cumsum(np.cumsum(padded, axis=0), axis=1, out=sat[1:, 1:])

        def box(r0: int, r1: int, c0: int, c1: int) -> np.ndarray:
            """Sum over row offsets r0..r1 and column offsets c0..c1 of every cell."""
            a0, a1 = h0 + r0, h0 + r1 + 1
            b0, b1 = h1 + c0, h1 + c1 + 1
            return (
                sat[a1 : a1 + nr, b1 : b1 + nd]
                - sat[a0 : a0 + nr, b1 : b1 + nd]
                - sat[a1 : a1 + nr, b0 : b0 + nd]
                + sat[a0 : a0 + nr, b0 : b0 + nd]
            )

        if self.method == "CA":
            total = box(-h0, h0, -h1, h1) - box(-g0, g0, -g1, g1)
            return (self.alpha / self.n_training) * total
        before = box(-h0, -1, -h1, h1) - (box(-g0, -1, -g1, g1) if g0 else 0.0)
        after = box(1, h0, -h1, h1) - (box(1, g0, -g1, g1) if g0 else 0.0)
        pick = np.minimum if self.method == "SO" else np.maximum
        return self.alpha * pick(before, after)

    def detect(self, power: np.ndarray) -> np.ndarray:
        """Boolean mask of cells above their threshold."""
        return np.asarray(power) > self.threshold(power)
