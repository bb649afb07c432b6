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

Two ways to evaluate: :meth:`Cfar2D.threshold` gives the threshold of every cell (summed-area
tables for CA/SO/GO, a gathered order statistic for OS); :meth:`Cfar2D.threshold_at` gives it
only at chosen cells by gathering their training cells, ``(K, N)``, from the padded map with
one fancy index. The processing chain tests only candidate cells (local maxima above a
pre-threshold, see :meth:`Cfar2D.prethreshold_fraction`), which makes OS as cheap as CA.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import brentq
from scipy.special import betainc, gammainc, gammaln

if TYPE_CHECKING:
    from lrp_gym.config import CfarConfig

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

    No defaults here: :meth:`from_config` builds it from the validated ``radar.cfar``
    (:class:`lrp_gym.config.CfarConfig` holds the defaults).
    """

    method: str
    guard: tuple[int, int]
    training: tuple[int, int]
    pfa: float
    os_rank: float

    @classmethod
    def from_config(cls, cfg: CfarConfig) -> Cfar2D:
        """The detector a scenario's ``radar.cfar`` section describes."""
        return cls(
            cfg.method,
            (cfg.guard_cells[0], cfg.guard_cells[1]),
            (cfg.training_cells[0], cfg.training_cells[1]),
            cfg.pfa,
            cfg.os_rank,
        )

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

    @property
    def expected_statistic(self) -> float:
        """Mean of the statistic ``S`` (threshold ``alpha S``) on unit-power noise, roughly.

        CA: the training mean (1); SO/GO: a half-ring sum (``n_half``); OS: the ``k/(N+1)``
        quantile of the exponential distribution.
        """
        if self.method == "CA":
            return 1.0
        if self.method in ("SO", "GO"):
            return float(self.n_half)
        return -math.log1p(-self.rank / (self.n_training + 1.0))

    def statistic_cdf(self, q: float) -> float:
        """``P(S < q)`` for unit-power exponential noise in all training cells."""
        if q <= 0.0:
            return 0.0
        n = self.n_training
        if self.method == "CA":
            return float(gammainc(n, n * q))  # the sum of n unit exponentials is Gamma(n)
        if self.method in ("SO", "GO"):
            half = float(gammainc(self.n_half, q))
            return 1.0 - (1.0 - half) ** 2 if self.method == "SO" else half**2
        # OS: X_(k) < q  <=>  at least k of the n cells are below q
        return float(betainc(self.rank, n - self.rank + 1, -math.expm1(-q)))

    @cached_property
    def prethreshold_fraction(self) -> float:
        """Noise-relative pre-threshold ``q`` that cannot change the false-alarm rate.

        A cell can only be detected when ``P > alpha S``. Screening with ``P > alpha q N0``
        (``N0`` the noise power of a cell) drops a would-be detection only when ``S < q N0``,
        so it lowers the false-alarm probability by at most ``P(S < q)``. ``q`` is the largest
        of a few fractions of the statistic's mean with ``P(S < q) <= 1e-3 pfa``: e.g. for
        the default OS window (N = 174, k = 131) ``q = 0.5 E[S]`` and ``P(S < q) ~ 1e-20``.
        """
        mean = self.expected_statistic
        for f in (0.5, 0.3, 0.2, 0.1, 0.05, 0.02, 0.01):
            if self.statistic_cdf(f * mean) <= 1e-3 * self.pfa:
                return f * mean
        return 0.0

    # ------------------------------------------------------------------ padded map + offsets
    @property
    def pad_width(self) -> tuple[int, int]:
        """Padding of :meth:`pad` along (range, Doppler): the half window, at least 1."""
        return (max(self.half_window[0], 1), max(self.half_window[1], 1))

    def pad(self, power: np.ndarray) -> np.ndarray:
        """Map padded by :attr:`pad_width`: range mirrored (symmetric), Doppler wrapped."""
        power = np.asarray(power)
        nr, nd = power.shape
        h0, h1 = self.pad_width
        if h0 > nr:
            raise ValueError("CFAR window is longer than the map")
        out = np.empty((nr + 2 * h0, nd + 2 * h1), dtype=power.dtype)
        out[h0 : h0 + nr, h1 : h1 + nd] = power
        out[:h0, h1 : h1 + nd] = power[h0 - 1 :: -1]
        out[h0 + nr :, h1 : h1 + nd] = power[: nr - h0 - 1 : -1] if nr > h0 else power[::-1]
        out[:, :h1] = out[:, nd : nd + h1]
        out[:, h1 + nd :] = out[:, h1 : 2 * h1]
        return out

    def _offsets(self, width: int) -> dict[str, np.ndarray]:
        """Flat offsets (in a padded map of ``width`` columns) of the training cells."""
        cache = self.__dict__.setdefault("_offset_cache", {})
        if width not in cache:
            (g0, g1), (h0, h1) = self.guard, self.half_window
            dr, dd = np.meshgrid(np.arange(-h0, h0 + 1), np.arange(-h1, h1 + 1), indexing="ij")
            ring = ~((np.abs(dr) <= g0) & (np.abs(dd) <= g1))
            flat = (dr * width + dd)[ring]
            cache[width] = {
                "all": flat,
                "before": (dr * width + dd)[ring & (dr < 0)],
                "after": (dr * width + dd)[ring & (dr > 0)],
            }
        return cache[width]

    def threshold_at(self, padded: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Thresholds of cells ``(rows, cols)`` (map coordinates) given the :meth:`pad` map.

        Gathers the training cells of the K cells into a (K, N) array with one fancy index;
        OS takes the k-th order statistic with :func:`numpy.partition`.
        """
        h0, h1 = self.pad_width
        width = padded.shape[1]
        centre = (np.asarray(rows) + h0) * width + (np.asarray(cols) + h1)
        flat = padded.reshape(-1)
        off = self._offsets(width)
        if self.method == "CA":
            s = flat[centre[:, None] + off["all"]].sum(axis=1) / self.n_training
        elif self.method == "OS":
            r = self.rank - 1
            s = np.partition(flat[centre[:, None] + off["all"]], r, axis=1)[:, r]
        else:
            before = flat[centre[:, None] + off["before"]].sum(axis=1)
            after = flat[centre[:, None] + off["after"]].sum(axis=1)
            s = np.minimum(before, after) if self.method == "SO" else np.maximum(before, after)
        return self.alpha * s

    def threshold(self, power: np.ndarray) -> np.ndarray:
        """Detection threshold for every cell of ``power`` (range x Doppler)."""
        power = np.asarray(power, dtype=np.float64)
        nr, nd = power.shape
        padded = self.pad(power)
        if self.method == "OS":
            rows, cols = np.divmod(np.arange(nr * nd), nd)
            out = np.empty(nr * nd)
            for s in range(0, nr * nd, 2048):  # bounded (chunk, N) memory
                out[s : s + 2048] = self.threshold_at(
                    padded, rows[s : s + 2048], cols[s : s + 2048]
                )
            return out.reshape(nr, nd)
        p0, p1 = self.pad_width
        (g0, g1), (h0, h1) = self.guard, self.half_window
        sat = np.zeros((padded.shape[0] + 1, padded.shape[1] + 1))
        np.cumsum(np.cumsum(padded, axis=0), axis=1, out=sat[1:, 1:])

        def box(r0: int, r1: int, c0: int, c1: int) -> np.ndarray:
            """Sum over row offsets r0..r1 and column offsets c0..c1 of every cell."""
            a0, a1 = p0 + r0, p0 + r1 + 1
            b0, b1 = p1 + c0, p1 + c1 + 1
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
