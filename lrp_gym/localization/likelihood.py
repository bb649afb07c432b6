"""Likelihood of an unordered set of measured distances per reflector type, for many poses.

The association between measured distances and reflectors is unknown; only the type of each
distance is known. Per type ``t`` with ``m`` reflectors and ``n`` measured distances
``z_1 <= ... <= z_n`` the model is

- *sorted* (all ``n == m`` distances are the reflectors'): the sorted-to-sorted assignment.
  In 1-D it is the assignment with the smallest sum of squared residuals, so it is the
  maximum-likelihood association of the paper's Gaussian model (``C = sigma^2 I``) without
  enumerating permutations: ``L_s = prod_i N(z_(i); e_(i), s_i^2)``;
- *mixture* (some distance is clutter, some reflector missed): each measured distance is
  explained by any of the particle's ``m`` expected distances of that type with equal
  probability, or by clutter: ``L_m = prod_i [(1 - c) mean_j N(z_i; e_j, s_i^2) + c / R]``,
  with ``c = clutter_probability`` and ``R`` the radar's maximum range.

The room's own strong returns (ceiling, wall-ceiling edges, walls; see
:mod:`lrp_gym.world.structure`) are predictable from the map too. With a ``room`` and a
``structure_probability`` ``s``, the reflector term of each factor becomes
``(1 - s) mean_j N(z_i; e_j) + s mean_k N(z_i; g_k)`` with ``g_k`` the particle's predicted
structure ranges, so a reflector-like return of the room counts as evidence for the particles
that predict it instead of as clutter that any particle may borrow.

When the counts match, ``L = (1 - c)^n L_s + (1 - (1 - c)^n) L_m`` (the probability that no
distance is clutter weights the exact assignment); when they differ, ``L = L_m``. The clutter
floor bounds what one wrong distance can cost a particle, and a missed-plus-clutter frame (equal
counts, wrong assignment) still scores the true pose through ``L_m``. ``s_i^2`` is the configured
measurement variance plus the tracker's reported variance of that distance. With ``c = 0`` the
model is the paper's pure Gaussian (sorted assignment, or the mixture when counts differ).

The result is invariant to the order of the measured distances (they are sorted first).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.room import Room
from lrp_gym.world.structure import structure_ranges_m

if TYPE_CHECKING:
    from lrp_gym.config import LocalizationConfig
    from lrp_gym.world.world import World

_LOG_SQRT_2PI = 0.5 * np.log(2.0 * np.pi)


_NETWORKS = {
    2: [(0, 1)],
    3: [(0, 1), (1, 2), (0, 1)],
    4: [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)],
}


def sort_rows_inplace(values: np.ndarray) -> np.ndarray:
    """Sort a (m, N) array along axis 0 (each column ascending), in place; returns it.

    For ``m <= 4`` a sorting network of ``np.minimum``/``np.maximum`` on contiguous rows is
    several times faster than ``np.sort(axis=0)``; beyond that ``np.sort``.
    """
    m = values.shape[0]
    if m <= 1:
        return values
    if m > 4:
        values.sort(axis=0)
        return values
    for i, j in _NETWORKS[m]:
        lo = np.minimum(values[i], values[j])
        np.maximum(values[i], values[j], out=values[j])
        values[i] = lo
    return values


class FingerprintModel:
    """Expected fingerprints and the measurement likelihood for floor positions.

    Parameters
    ----------
    layout : ReflectorLayout
        The reflectors (positions and types).
    mount_height_m : float
        Radar height above the floor; the height differences to the reflectors are constant
        and precomputed.
    measurement_std_m : float
        Standard deviation of a measured distance (added in quadrature to the tracker's).
    clutter_probability : float
        Probability that a measured distance is clutter (uniform over ``[0, max_range_m]``).
    max_range_m : float
        Support of the clutter density.
    room : Room, optional
        The room whose structure returns the model predicts (with ``structure_probability``).
    structure_probability : float
        Probability that a measured distance is a structure return of the room.
    """

    def __init__(
        self,
        layout: ReflectorLayout,
        mount_height_m: float,
        measurement_std_m: float = 0.075,
        clutter_probability: float = 0.05,
        max_range_m: float = 20.0,
        room: Room | None = None,
        structure_probability: float = 0.0,
    ) -> None:
        self.room = room
        self.mount_height_m = float(mount_height_m)
        self.structure_probability = float(structure_probability) if room is not None else 0.0
        self.type_names = layout.type_names
        self._xy = []
        self._dz2 = []
        for t in range(len(layout.types)):
            sel = layout.type_index == t
            self._xy.append(layout.positions_m[sel, :2].copy())
            self._dz2.append((layout.positions_m[sel, 2] - mount_height_m) ** 2)
        self.counts = tuple(len(x) for x in self._xy)
        self.measurement_var_m2 = float(measurement_std_m) ** 2
        self.clutter_probability = float(clutter_probability)
        self.clutter_density = 1.0 / float(max_range_m)

    @classmethod
    def for_world(cls, world: World, cfg: LocalizationConfig) -> FingerprintModel:
        """The localisers' model of ``world``: its layout, radar height and range, and room
        structure, with the measurement, clutter and structure settings of ``cfg``."""
        return cls(
            world.layout,
            world.mount_height_m,
            cfg.measurement_std_m,
            cfg.clutter_probability,
            world.fmcw.max_range_m,
            room=world.room,
            structure_probability=cfg.structure_probability,
        )

    def expected(self, xy: np.ndarray, dtype=np.float64) -> list[np.ndarray]:
        """Sorted expected distances per type for positions (N, 2): list of (m_t, N) arrays.

        Reflector-major layout: each row is contiguous, so the sorting network and the
        per-distance arithmetic work on whole rows with few numpy calls.
        """
        x = xy[:, 0].astype(dtype)
        y = xy[:, 1].astype(dtype)
        out = []
        for rxy, dz2 in zip(self._xy, self._dz2, strict=True):
            dx = x - rxy[:, 0:1].astype(dtype)
            dx *= dx
            dy = y - rxy[:, 1:2].astype(dtype)
            dy *= dy
            dx += dy
            dx += dz2[:, None].astype(dtype)
            out.append(sort_rows_inplace(np.sqrt(dx, out=dx)))
        return out

    def log_likelihood(
        self, xy: np.ndarray, fingerprint: Fingerprint, dtype=np.float32
    ) -> np.ndarray:
        """Log-likelihood (N,) float64 of ``fingerprint`` at each position of ``xy`` (N, 2).

        Types are matched by name; a type the layout does not have is ignored (its distances
        carry the same clutter factor for every particle). The per-particle arithmetic runs in
        ``dtype`` (float32 by default: SIMD ``exp`` is several times faster, and distances in a
        room keep sub-micrometre precision); the per-type sums are float64.
        """
        n_pos = xy.shape[0]
        out = np.zeros(n_pos)
        expected = None
        structure = None
        c = self.clutter_probability
        s_prob = self.structure_probability
        for name, z, var in zip(
            fingerprint.type_names, fingerprint.distances_m, fingerprint.variances_m2, strict=True
        ):
            if len(z) == 0 or name not in self.type_names:
                continue
            t = self.type_names.index(name)
            m = self.counts[t]
            if m == 0:
                continue
            if expected is None:
                expected = self.expected(xy, dtype)
            e = expected[t]  # (m, N), sorted along axis 0
            order = np.argsort(z)
            z = np.asarray(z, dtype=float)[order]
            s2 = self.measurement_var_m2 + np.asarray(var, dtype=float)[order]
            half_inv = (-0.5 / s2).astype(dtype)[:, None]
            log_norm = -0.5 * np.log(2.0 * np.pi * s2)
            n = len(z)
            ln_scale = log_norm.astype(dtype)[:, None]
            # r[i, j] = half_inv_i (e_j - z_i)^2 for every measured i and expected j.
            r = e[None, :, :] - z.astype(dtype)[:, None, None]  # (n, m, N)
            r *= r
            r *= half_inv[:, :, None]
            log_sorted = None
            if n == m:  # diagonal = sorted-to-sorted assignment (e and z both ascending)
                diag = r[np.arange(n), np.arange(n)]
                diag += ln_scale
                log_sorted = diag.sum(axis=0, dtype=np.float64)
            if c == 0.0:
                if log_sorted is None:  # no clutter floor: the mixture in the log domain
                    mix = np.logaddexp.reduce(r, axis=1) + ln_scale - dtype(np.log(m))
                    log_sorted = mix.sum(axis=0, dtype=np.float64)
                out += log_sorted
                continue
            np.exp(r, out=r)
            g = r.mean(axis=1)  # (n, N)
            if s_prob > 0.0:
                if structure is None:
                    structure = structure_ranges_m(self.room, self.mount_height_m, xy).astype(dtype)
                rs = structure[None, :, :] - z.astype(dtype)[:, None, None]  # (n, 9, N)
                rs *= rs
                rs *= half_inv[:, :, None]
                np.exp(rs, out=rs)
                g *= dtype(1.0 - s_prob)
                g += dtype(s_prob) * rs.mean(axis=1)
            g *= ((1.0 - c) * np.exp(log_norm)).astype(dtype)[:, None]
            g += dtype(c * self.clutter_density)
            # Every factor is >= the clutter floor: chunks of 8 cannot underflow in float32.
            log_mix = np.zeros(n_pos)
            for k in range(0, n, 8):
                log_mix += np.log(np.prod(g[k : k + 8], axis=0))
            if log_sorted is None:
                out += log_mix
                continue
            # All n distances are reflectors with probability (1 - c)^n: sorted assignment;
            # otherwise at least one is clutter (and one reflector missed): the mixture.
            p_clean = ((1.0 - c) * (1.0 - s_prob)) ** n
            out += np.logaddexp(np.log(p_clean) + log_sorted, np.log1p(-p_clean) + log_mix)
        return out

    def distance_fits(
        self, xy: np.ndarray, weights: np.ndarray, fingerprint: Fingerprint
    ) -> np.ndarray:
        """How well the weighted positions explain each measured distance, each in [0, 1].

        For each measured distance (types in fingerprint order, distances in their given
        order), the weighted mean over the positions ``xy`` (N, 2) of ``exp(-r^2 / (2 s^2))``,
        with ``r`` the residual to the *nearest* expected distance of its type and ``s^2`` its
        variance (as in :meth:`log_likelihood`). An exact distance at the true pose scores 1,
        a clutter distance about 0; a posterior far from the truth scores only the chance
        coincidences. A type with ``m`` reflectors can explain at most ``m`` distances, so only
        its ``m`` best fits are kept (the rest are clutter whatever the pose). Returned in
        descending order per type, types in fingerprint order. Distances of a type the layout
        lacks are left out; empty if none is left or the weights sum to 0.
        """
        total_w = float(np.sum(weights))
        out: list[np.ndarray] = []
        if not total_w > 0.0:
            return np.zeros(0)
        expected = None
        for name, z, var in zip(
            fingerprint.type_names, fingerprint.distances_m, fingerprint.variances_m2, strict=True
        ):
            if len(z) == 0 or name not in self.type_names:
                continue
            t = self.type_names.index(name)
            if self.counts[t] == 0:
                continue
            if expected is None:
                expected = self.expected(xy, np.float32)
            z = np.asarray(z, dtype=np.float32)
            half_inv = (-0.5 / (self.measurement_var_m2 + np.asarray(var, float))).astype(
                np.float32
            )
            r = expected[t][None, :, :] - z[:, None, None]  # (n, m, N)
            r *= r
            r2 = r.min(axis=1)  # squared residual to the nearest expected distance (n, N)
            r2 *= half_inv[:, None]
            fits = np.exp(r2, out=r2) @ (weights / total_w)
            out.append(-np.sort(-fits)[: self.counts[t]])
        return np.concatenate(out) if out else np.zeros(0)
