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
the clutter term by the density of a mostly static scatterer's radial velocity (the robot's
speed on an unknown line of sight, uniform over ``+-|v|``, blurred by the same ``s_v``). A
static reflector at horizontal offset ``p_j - x`` and range ``e_j`` closes at ``u_j = -v .
(p_j - x) / e_j``: the heading enters through the velocity ``v``. With a
``detection_probability`` ``P_D``, each mapped reflector adds ``log(P_D k_j + 1 - P_D)``,
``k_j`` its best match's kernel among the distances of any type (negative information); with
a ``visibility`` model, ``P_D`` times the radar's probability ``p_j`` of detecting that
reflector from the position (:mod:`~lrp_gym.localization.visibility`), and a reflector the
position cannot see is left out of the terms above; clutter and room returns keep their
expected numbers, so where ``m_s`` of a type's ``m`` reflectors are seen, the shares of a
distance are divided by ``1 - r (m - m_s) / m`` (``r`` the reflectors' share with all seen).
Invariant to the order of the distances; the array code is in
:mod:`~lrp_gym.localization.likelihood_terms`, the map's in :mod:`~lrp_gym.localization.map_returns`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from lrp_gym.localization import likelihood_terms as terms
from lrp_gym.localization.map_returns import MapReturns
from lrp_gym.localization.reflector_ranges import ReflectorRanges
from lrp_gym.localization.visibility import (
    RadarLink,
    ReflectorVisibility,
    VisibilityMap,
)
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.room import Room

if TYPE_CHECKING:
    from lrp_gym.config import LocalizationConfig
    from lrp_gym.world.world import World


@dataclass(frozen=True)
class Segment:
    """The measured distances of one reflector type, sorted ascending.

    Attributes
    ----------
    type_index : int
        The type's index in the layout.
    z : ndarray (n,)
        Distances.
    s2 : ndarray (n,)
        Their variances: the model's measurement variance plus the tracker's.
    v : ndarray (n,) or None
        Their radial velocities when the Doppler term applies, else None.
    """

    type_index: int
    z: np.ndarray
    s2: np.ndarray
    v: np.ndarray | None


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
        (:mod:`lrp_gym.localization.ghosts`); needs ``room``. ``ghost_weights`` (G,) share it
        among the predicted ghosts (:class:`MapReturns`); None: equally.
    use_numba : bool
        Evaluate the map-return density with the numba kernel of
        :mod:`lrp_gym.localization._map_kernel` when numba is installed (else numpy).
    visibility : VisibilityMap or ReflectorVisibility, optional
        How likely the radar is to detect each reflector from a position (obstacles,
        pattern, range, SNR). A reflector's silence costs ``log(1 - P_D p_j)`` with ``p_j``
        that probability; a hidden one (``p_j`` below 0.01) has the expected range
        :data:`~lrp_gym.localization.visibility.HIDDEN_RANGE_M` (it sorts last) and explains
        no distance. None: every reflector is detected with ``P_D`` everywhere.
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
        ghost_weights: np.ndarray | None = None,
        use_numba: bool = True,
        visibility: ReflectorVisibility | VisibilityMap | None = None,
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
        self.map_returns: MapReturns | None = None
        if room is not None and self.structure_probability + self.ghost_probability > 0.0:
            probabilities = (self.structure_probability, self.ghost_probability)
            self.map_returns = MapReturns(
                room, layout, mount_height_m, *probabilities, ghost_weights
            )
        self.ghosts = None if self.map_returns is None else self.map_returns.ghosts
        self.type_names = layout.type_names
        #: The reflectors' ranges from positions, and which ones each position sees.
        self.reflectors = ReflectorRanges(layout, mount_height_m, visibility)
        self.counts = self.reflectors.counts
        self.measurement_var_m2 = float(measurement_std_m) ** 2
        self.clutter_probability = float(clutter_probability)
        self.clutter_density = 1.0 / float(max_range_m)

    @classmethod
    def for_world(
        cls, world: World, cfg: LocalizationConfig, link: RadarLink | None = None
    ) -> FingerprintModel:
        """The localisers' model of ``world``: its layout, radar height and range, and room
        structure, with the measurement, clutter and structure settings of ``cfg``; with the
        radar's ``link`` budget, each reflector's detection probability from its SNR (and
        the ghosts' weights, when it carries surveyed ones)."""
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
            ghost_weights=None if link is None else link.ghost_weights,
            visibility=(
                ReflectorVisibility.for_world(world, link) if cfg.reflector_visibility else None
            ),
        )

    @property
    def visibility(self) -> ReflectorVisibility | VisibilityMap | None:
        """The detection model of :attr:`reflectors` (None: every reflector everywhere)."""
        return self.reflectors.visibility

    @property
    def link(self) -> RadarLink | None:
        """The radar link budget behind the detection probabilities, if any."""
        return None if self.visibility is None else self.visibility.link

    @property
    def clean_probability(self) -> float:
        """Probability that a measured distance is a reflector's (neither clutter nor a map
        return): ``(1 - c)(1 - s - g)``."""
        map_p = 0.0 if self.map_returns is None else self.map_returns.probability
        return (1.0 - self.clutter_probability) * (1.0 - map_p)

    def clutter_density_for(
        self, doppler: bool, speed_mps: float = 0.0, velocities_mps: np.ndarray | None = None
    ) -> float | np.ndarray:
        """Density of a clutter return: uniform in range and, with Doppler, times the density
        of its radial velocity (``likelihood_terms.clutter_velocity_density``), one per
        measured velocity in ``velocities_mps`` (n,), else its value at zero velocity."""
        if not doppler:
            return self.clutter_density
        return self.clutter_density * terms.clutter_velocity_density(
            speed_mps, self.doppler_std_mps, self.velocity_density, velocities_mps
        )

    def doppler_coefficients(self) -> tuple[float, float, float]:
        """(a, b, c) of the Doppler density (``velocity_density_coefficients``)."""
        return terms.velocity_density_coefficients(
            self.doppler_std_mps, self.doppler_outlier_probability, self.velocity_density
        )

    def expected(
        self, xy: np.ndarray, dtype=np.float64, p_detect: np.ndarray | None = None
    ) -> list[np.ndarray]:
        """:meth:`ReflectorRanges.expected`: sorted expected distances per type."""
        return self.reflectors.expected(xy, dtype, p_detect)

    def map_return_ranges(self, xy: np.ndarray, dtype=np.float32) -> np.ndarray | None:
        """Ranges (K, N) of the map-predicted non-reflector returns at positions (N, 2), to
        pass as ``map_ranges`` to :meth:`log_likelihood` for positions that do not move (a
        fixed grid); None when the model predicts none."""
        if self.map_returns is None:
            return None
        return self.map_returns.ranges(xy, None, dtype)[0]

    def map_returns_at(
        self,
        xy: np.ndarray,
        fingerprint: Fingerprint,
        velocity_xy: np.ndarray | None,
        dtype=np.float32,
    ) -> tuple[np.ndarray, np.ndarray | None] | None:
        """Ranges (K, N) of the map-predicted returns at positions (N, 2) and, where the
        Doppler term of :meth:`log_likelihood` applies to ``fingerprint`` at ``velocity_xy``
        (N, 2), their radial velocities (K, N), else None: the ``map_ranges`` and
        ``map_rates`` of several calls on these positions or on a subset of their columns (a
        range does not depend on the velocity). None when the model predicts no returns."""
        if self.map_returns is None:
            return None
        doppler = (
            velocity_xy is not None
            and self.doppler_std_mps > 0.0
            and fingerprint.velocities_mps is not None
        )
        return self.map_returns.ranges(xy, velocity_xy if doppler else None, dtype)

    def segments(self, fingerprint: Fingerprint, doppler: bool) -> list[Segment]:
        """The fingerprint's distances per type that the likelihood weighs, sorted: types the
        layout lacks (their distances carry the same clutter factor for every position),
        empty types and types without reflectors are left out."""
        out = []
        velocities = fingerprint.velocities_mps
        for k, (name, z, var) in enumerate(
            zip(
                fingerprint.type_names,
                fingerprint.distances_m,
                fingerprint.variances_m2,
                strict=True,
            )
        ):
            if len(z) == 0 or name not in self.type_names:
                continue
            t = self.type_names.index(name)
            if self.counts[t] == 0:
                continue
            order = np.argsort(z)
            s2 = self.measurement_var_m2 + np.asarray(var, dtype=float)[order]
            v = np.asarray(velocities[k], dtype=float)[order] if doppler and velocities else None
            out.append(Segment(t, np.asarray(z, dtype=float)[order], s2, v))
        return out

    def log_likelihood(
        self,
        xy: np.ndarray,
        fingerprint: Fingerprint,
        dtype=np.float32,
        velocity_xy: np.ndarray | None = None,
        map_ranges: np.ndarray | None = None,
        map_rates: np.ndarray | None = None,
        expected: list[np.ndarray] | None = None,
        p_detect: np.ndarray | None = None,
    ) -> np.ndarray:
        """Log-likelihood (N,) float64 of ``fingerprint`` at each position of ``xy`` (N, 2).

        Types are matched by name; a type the layout does not have is ignored (its distances
        carry the same clutter factor for every particle). ``velocity_xy`` (N, 2), the velocity
        of each position's robot over the floor, adds the Doppler term when the model has a
        ``doppler_std_mps`` and the fingerprint carries velocities. The per-position
        arithmetic runs in ``dtype`` (float32 by default: SIMD ``exp`` is several times
        faster, and distances in a room keep sub-micrometre precision); the sums are float64.
        ``map_ranges``, :meth:`map_return_ranges` of ``xy``, saves recomputing them where the
        Doppler term does not apply; where it does, they are used only together with
        ``map_rates``, their radial velocities at ``velocity_xy`` (:meth:`map_returns_at`),
        and computed with their velocities otherwise. ``expected``, :meth:`expected` of ``xy``
        in ``dtype``, likewise saves recomputing the reflectors' ranges where the Doppler term
        does not apply (it is ignored where it does). ``p_detect``, the reflectors'
        :meth:`ReflectorRanges.detection_probabilities` at ``xy``, saves recomputing them.
        """
        doppler = (
            velocity_xy is not None
            and self.doppler_std_mps > 0.0
            and fingerprint.velocities_mps is not None
        )
        vel = velocity_xy if doppler else None
        segments = self.segments(fingerprint, doppler)
        if not segments:
            return np.zeros(xy.shape[0])
        given = None
        if map_ranges is not None and (vel is None or map_rates is not None):
            given = (map_ranges, None if vel is None else map_rates)
        expected = expected if vel is None else None
        return terms.log_likelihood_terms(self, xy, segments, vel, given, dtype, expected, p_detect)

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


def frame_fit(fits: np.ndarray) -> float | None:
    """One frame's measurement fit from :meth:`FingerprintModel.distance_fits`: their mean,
    leaving out the worst of three or more (a missed reflector plus a clutter distance), at
    least 1e-12; None without any distance."""
    if len(fits) == 0:
        return None
    if len(fits) >= 3:
        fits = np.delete(fits, np.argmin(fits))
    return max(float(np.mean(fits)), 1e-12)
