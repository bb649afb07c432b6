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

With Doppler (``doppler_std_mps > 0``, a fingerprint that carries radial velocities and the
particles' velocity vectors), each reflector or structure term is multiplied by the density of
the measured radial velocity ``v_i`` given the one the particle predicts for that return,
``(1 - q) N(v_i; u_j, s_v^2) + q / (2 v_max)`` (``q`` the Doppler outlier probability), and
the clutter term by ``1 / (2 v_max)``. A static reflector at horizontal offset ``p_j - x`` and
range ``e_j`` closes at ``u_j = -v . (p_j - x) / e_j``: the robot's heading enters through its
velocity ``v``, so moving frames weigh the heading hypotheses that the distances alone cannot.

The result is invariant to the order of the measured distances (they are sorted first).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from lrp_gym.localization._map_kernel import map_return_density
from lrp_gym.localization.ghosts import GhostModel
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.room import Room
from lrp_gym.world.structure import (
    N_STRUCTURE_RETURNS,
    structure_ranges_m,
    structure_velocities_mps,
)

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


def sort_rows_paired_inplace(values: np.ndarray, companion: np.ndarray) -> None:
    """Sort ``values`` (m, N) along axis 0 in place and permute ``companion`` alongside."""
    m = values.shape[0]
    if m <= 1:
        return
    if m > 4:
        order = np.argsort(values, axis=0)
        values[:] = np.take_along_axis(values, order, axis=0)
        companion[:] = np.take_along_axis(companion, order, axis=0)
        return
    for i, j in _NETWORKS[m]:
        swap = values[i] > values[j]
        lo = np.minimum(values[i], values[j])
        np.maximum(values[i], values[j], out=values[j])
        values[i] = lo
        ci = np.where(swap, companion[j], companion[i])
        np.copyto(companion[j], companion[i], where=swap)
        companion[i] = ci


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
    doppler_std_mps : float
        Standard deviation of a measured radial velocity; 0 leaves the Doppler out.
    doppler_outlier_probability : float
        Probability that a return's velocity is unrelated to its predicted one (a wrong
        Doppler peak), uniform over ``[-max_velocity_mps, max_velocity_mps]``.
    max_velocity_mps : float
        The radar's unambiguous velocity.
    detection_probability : float
        Probability that a reflector in view yields a detection; a reflector that no measured
        distance of its type matches costs ``1 - P_D`` (0 leaves this term out).
    ghost_probability : float
        Probability that a measured distance is a reflector seen via a wall or the ceiling
        (:mod:`lrp_gym.localization.ghosts`); needs ``room``.
    use_numba : bool
        Evaluate the room-structure and ghost terms with the compiled kernel of
        :mod:`lrp_gym.localization._map_kernel` when numba is installed.
    """

    def __init__(
        self,
        layout: ReflectorLayout,
        mount_height_m: float,
        measurement_std_m: float,
        clutter_probability: float,
        max_range_m: float,
        room: Room | None = None,
        structure_probability: float = 0.0,
        doppler_std_mps: float = 0.0,
        doppler_outlier_probability: float = 0.1,
        max_velocity_mps: float = 5.0,
        detection_probability: float = 0.0,
        ghost_probability: float = 0.0,
        use_numba: bool = True,
    ) -> None:
        self.use_numba = use_numba
        self.room = room
        self.detection_probability = float(detection_probability)
        self.doppler_std_mps = float(doppler_std_mps)
        self.doppler_outlier_probability = float(doppler_outlier_probability)
        self.velocity_density = 0.5 / float(max_velocity_mps)
        self.mount_height_m = float(mount_height_m)
        self.structure_probability = float(structure_probability) if room is not None else 0.0
        self.ghost_probability = float(ghost_probability) if room is not None else 0.0
        if self.structure_probability + self.ghost_probability > 1.0:
            raise ValueError(
                "structure_probability + ghost_probability must be <= 1, got "
                f"{self.structure_probability} + {self.ghost_probability}"
            )
        self.ghosts = (
            GhostModel(room, layout, mount_height_m)
            if room is not None and self.ghost_probability > 0.0
            else None
        )
        self._extra_weights = self._map_return_weights()
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
            doppler_std_mps=cfg.doppler_std_mps,
            doppler_outlier_probability=cfg.doppler_outlier_probability,
            max_velocity_mps=world.fmcw.max_velocity_mps,
            detection_probability=cfg.detection_probability,
            ghost_probability=cfg.ghost_probability,
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

    def expected_with_velocity(
        self, xy: np.ndarray, velocity_xy: np.ndarray, dtype=np.float32
    ) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """Sorted expected distances and, alongside, radial velocities per type.

        ``velocity_xy`` (N, 2) is each position's velocity over the floor; the radial velocity
        of a reflector is positive when its distance grows. Lists of (m_t, N) arrays.
        """
        x = xy[:, 0].astype(dtype)
        y = xy[:, 1].astype(dtype)
        vx = velocity_xy[:, 0].astype(dtype)
        vy = velocity_xy[:, 1].astype(dtype)
        ranges, rates = [], []
        for rxy, dz2 in zip(self._xy, self._dz2, strict=True):
            dx = rxy[:, 0:1].astype(dtype) - x
            dy = rxy[:, 1:2].astype(dtype) - y
            d = np.sqrt(dx * dx + dy * dy + dz2[:, None].astype(dtype))
            rate = -(vx * dx + vy * dy) / d
            sort_rows_paired_inplace(d, rate)
            ranges.append(d)
            rates.append(rate)
        return ranges, rates

    def _doppler_coefficients(self) -> tuple[float, float, float]:
        """(a, b, c) of the Doppler density ``a exp(c dv^2) + b`` (see :meth:`_doppler_density`)."""
        s = self.doppler_std_mps
        q = self.doppler_outlier_probability
        if s <= 0.0:
            return 1.0, 0.0, 0.0
        return (1.0 - q) / (np.sqrt(2.0 * np.pi) * s), q * self.velocity_density, -0.5 / s**2

    def _doppler_density(self, v: np.ndarray, expected_v: np.ndarray, dtype) -> np.ndarray:
        """Density of measured velocities ``v`` (n,) given expected ones (k, N): (n, k, N)."""
        s = self.doppler_std_mps
        q = self.doppler_outlier_probability
        dv = expected_v[None, :, :] - v.astype(dtype)[:, None, None]
        dv *= dv
        dv *= dtype(-0.5 / s**2)
        np.exp(dv, out=dv)
        dv *= dtype((1.0 - q) / (np.sqrt(2.0 * np.pi) * s))
        dv += dtype(q * self.velocity_density)
        return dv

    def _map_return_weights(self) -> np.ndarray | None:
        """Mixture weight (K,) of each return of :meth:`_map_returns`; None without any."""
        parts = []
        if self.structure_probability > 0.0:
            parts.append(
                np.full(N_STRUCTURE_RETURNS, self.structure_probability / N_STRUCTURE_RETURNS)
            )
        if self.ghosts is not None:
            parts.append(np.full(self.ghosts.count, self.ghost_probability / self.ghosts.count))
        return np.concatenate(parts) if parts else None

    def _map_returns(
        self, xy: np.ndarray, velocity_xy: np.ndarray | None, dtype
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Ranges (K, N) of the non-reflector returns that the map predicts (room structure,
        then reflector ghosts) and their radial velocities (K, N) given ``velocity_xy``."""
        ranges, rates = [], []
        room = self.room  # not None when structure_probability > 0 (see __init__)
        if room is not None and self.structure_probability > 0.0:
            ranges.append(structure_ranges_m(room, self.mount_height_m, xy).astype(dtype))
            if velocity_xy is not None:
                rates.append(
                    structure_velocities_mps(room, self.mount_height_m, xy, velocity_xy).astype(
                        dtype
                    )
                )
        if self.ghosts is not None:
            g, gv = self.ghosts.ranges(xy, velocity_xy, dtype)
            ranges.append(g)
            if gv is not None:
                rates.append(gv)
        r = np.concatenate(ranges) if len(ranges) > 1 else ranges[0]
        if velocity_xy is None:
            return r, None
        return r, (np.concatenate(rates) if len(rates) > 1 else rates[0])

    def map_return_ranges(self, xy: np.ndarray, dtype=np.float32) -> np.ndarray | None:
        """Ranges (K, N) of the map-predicted non-reflector returns at positions (N, 2), to
        pass as ``map_ranges`` to :meth:`log_likelihood` for positions that do not move (a
        fixed grid); None when the model predicts none."""
        if self._extra_weights is None:
            return None
        return self._map_returns(xy, None, dtype)[0]

    def log_likelihood(
        self,
        xy: np.ndarray,
        fingerprint: Fingerprint,
        dtype=np.float32,
        velocity_xy: np.ndarray | None = None,
        map_ranges: np.ndarray | None = None,
    ) -> np.ndarray:
        """Log-likelihood (N,) float64 of ``fingerprint`` at each position of ``xy`` (N, 2).

        Types are matched by name; a type the layout does not have is ignored (its distances
        carry the same clutter factor for every particle). ``velocity_xy`` (N, 2), the velocity
        of each position's robot over the floor, adds the Doppler term when the model has a
        ``doppler_std_mps`` and the fingerprint carries velocities. The per-particle arithmetic runs in
        ``dtype`` (float32 by default: SIMD ``exp`` is several times faster, and distances in a
        room keep sub-micrometre precision); the per-type sums are float64. ``map_ranges``,
        :meth:`map_return_ranges` of ``xy``, saves recomputing them where the Doppler term does
        not apply (else they are computed with their velocities).
        """
        n_pos = xy.shape[0]
        out = np.zeros(n_pos)
        expected = None
        extra = extra_v = None
        c = self.clutter_probability
        s_prob = self.structure_probability
        gh_prob = self.ghost_probability
        extra_w = self._extra_weights
        measured_v = fingerprint.velocities_mps
        # The robot's velocity when the Doppler term applies, else None.
        doppler_xy = velocity_xy if self.doppler_std_mps > 0.0 and measured_v is not None else None
        doppler = doppler_xy is not None
        if map_ranges is not None and not doppler:
            extra = map_ranges.astype(dtype, copy=False)
        velocities: tuple[np.ndarray | None, ...] = (
            measured_v
            if doppler and measured_v is not None
            else (None,) * len(fingerprint.type_names)
        )
        clutter_density = self.clutter_density * (self.velocity_density if doppler else 1.0)
        for name, z, var, vel in zip(
            fingerprint.type_names,
            fingerprint.distances_m,
            fingerprint.variances_m2,
            velocities,
            strict=True,
        ):
            if len(z) == 0 or name not in self.type_names:
                continue
            t = self.type_names.index(name)
            m = self.counts[t]
            if m == 0:
                continue
            if expected is None:
                if doppler_xy is not None:
                    expected, expected_v = self.expected_with_velocity(xy, doppler_xy, dtype)
                else:
                    expected = self.expected(xy, dtype)
            e = expected[t]  # (m, N), sorted along axis 0
            order = np.argsort(z)
            z = np.asarray(z, dtype=float)[order]
            dens_v = None
            if doppler:
                v_sorted = np.asarray(vel)[order]
                dens_v = self._doppler_density(v_sorted, expected_v[t], dtype)
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
                if dens_v is not None:
                    diag += np.log(dens_v[np.arange(n), np.arange(n)])
                log_sorted = diag.sum(axis=0, dtype=np.float64)
            if c == 0.0:
                if log_sorted is None:  # no clutter floor: the mixture in the log domain
                    mix = np.logaddexp.reduce(r, axis=1) + ln_scale - dtype(np.log(m))
                    log_sorted = mix.sum(axis=0, dtype=np.float64)
                out += log_sorted
                continue
            np.exp(r, out=r)
            if self.detection_probability > 0.0:
                # Negative information: a reflector that no measured distance matches was
                # missed, which a pose that predicts it visible explains with 1 - P_D only.
                p_d = dtype(self.detection_probability)
                matched = r.max(axis=0)  # (m, N): kernel of each reflector's best match
                matched *= p_d
                matched += dtype(1.0) - p_d
                out += np.log(matched).sum(axis=0, dtype=np.float64)
            if dens_v is not None:
                r *= dens_v
            g = r.mean(axis=1)  # (n, N)
            if extra_w is not None:
                if extra is None:
                    extra, extra_v = self._map_returns(xy, doppler_xy, dtype)
                g *= dtype(1.0 - s_prob - gh_prob)
                g += map_return_density(
                    z,
                    half_inv[:, 0],
                    extra,
                    extra_w,
                    v_sorted if doppler else None,
                    extra_v,
                    self._doppler_coefficients(),
                    self.use_numba,
                )
            g *= ((1.0 - c) * np.exp(log_norm)).astype(dtype)[:, None]
            g += dtype(c * clutter_density)
            # Every factor is >= the clutter floor: chunks of 8 cannot underflow in float32.
            log_mix = np.zeros(n_pos)
            for k in range(0, n, 8):
                log_mix += np.log(np.prod(g[k : k + 8], axis=0))
            if log_sorted is None:
                out += log_mix
                continue
            # All n distances are reflectors with probability (1 - c)^n: sorted assignment;
            # otherwise at least one is clutter (and one reflector missed): the mixture.
            p_clean = ((1.0 - c) * (1.0 - s_prob - gh_prob)) ** n
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
