"""The terms of the fingerprint log-likelihood of :mod:`lrp_gym.localization.likelihood`:
whole (distances x reflectors x positions) arrays per type.

The per-position arithmetic runs in ``dtype`` (float32: SIMD
``exp`` is several times faster, and distances in a room keep sub-micrometre precision); the
sums over distances are float64.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy.special import ndtr

from lrp_gym.localization._map_kernel import map_return_density

if TYPE_CHECKING:
    from lrp_gym.localization.likelihood import FingerprintModel, Segment


#: Share of clutter returns whose radial velocity is not the robot's own motion (moving things,
#: another radar's interference): uniform over the radar's unambiguous interval.
MOVING_CLUTTER_SHARE = 0.1


def clutter_velocity_density(
    speed_mps: float,
    doppler_std_mps: float,
    uniform: float,
    v: np.ndarray | float | None = None,
) -> np.ndarray | float:
    """Density of a clutter return's radial velocity ``v`` (1 / (m/s)).

    Clutter is mostly static (furniture, room corners, a pillar): its true radial velocity is
    the robot's own speed projected on the line of sight, spread over ``+-|speed_mps|``
    (uniform: the azimuths and heights of unmapped scatterers are unknown), and it is measured
    with the same velocity noise ``doppler_std_mps`` as a mapped return. The static part is
    that box convolved with the noise, ``(Phi((v + s) / sigma) - Phi((v - s) / sigma)) / (2 s)``,
    so a return whose velocity any pose could predict is as likely as clutter as it is as a
    chance match: the Doppler term then adds evidence only where the predicted velocity is
    closer than chance. Only :data:`MOVING_CLUTTER_SHARE` of it spreads over the radar's whole
    unambiguous interval (density ``uniform``). Spreading all of it there would make clutter
    about 20 times less likely per return than any pose's match at walking speed (session 8);
    a box of half width ``|s| + 2 sigma`` (session 8 to 10) was still half as dense as static
    clutter near zero velocity at the pursuit's creeping 0.3 m/s, so every chance match of an
    unmapped scatterer counted for the pose that made it (docs/robustness.md).

    Without ``v`` the density at ``v = 0`` (its largest value) is returned.
    """
    s = min(abs(float(speed_mps)), 0.5 / uniform)  # no faster than the unambiguous interval
    sigma = max(float(doppler_std_mps), 1e-6)
    x = np.zeros(1) if v is None else np.asarray(v, dtype=float)
    if s < 1e-6 * sigma:
        static = np.exp(-0.5 * (x / sigma) ** 2) / (np.sqrt(2.0 * np.pi) * sigma)
    else:
        static = (ndtr((x + s) / sigma) - ndtr((x - s) / sigma)) / (2.0 * s)
    out = (1.0 - MOVING_CLUTTER_SHARE) * static + MOVING_CLUTTER_SHARE * uniform
    if v is None:
        return float(out[0])
    return out if np.ndim(v) else float(out)


def velocity_density_coefficients(
    std_mps: float, outlier_probability: float, uniform: float
) -> tuple[float, float, float]:
    """(a, b, c) of the density ``a exp(c dv^2) + b`` of a return's measured radial velocity
    ``dv`` off the one predicted: a Gaussian of ``std_mps``, plus the share
    ``outlier_probability`` spread uniformly (density ``uniform``, 1/(m/s)) over the radar's
    velocity span. ``std_mps`` 0: no Doppler term (density 1)."""
    if std_mps <= 0.0:
        return 1.0, 0.0, 0.0
    q = outlier_probability
    return (1.0 - q) / (np.sqrt(2.0 * np.pi) * std_mps), q * uniform, -0.5 / std_mps**2


def doppler_density(
    v: np.ndarray, expected_v: np.ndarray, coefficients: tuple[float, float, float], dtype
) -> np.ndarray:
    """Density ``a exp(c dv^2) + b`` (n, k, N) of measured velocities ``v`` (n,) given
    expected ones (k, N), with ``coefficients = (a, b, c)``
    (:func:`velocity_density_coefficients`)."""
    a, b, c = coefficients
    dv = expected_v[None, :, :] - v.astype(dtype)[:, None, None]
    dv *= dv
    dv *= dtype(c)
    np.exp(dv, out=dv)
    dv *= dtype(a)
    dv += dtype(b)
    return dv


class _Frame:
    """What the types of one frame share: positions, the expected ranges (computed on first
    use) and the map's predicted returns (computed on first use, or given)."""

    def __init__(self, model, xy, velocity_xy, map_returns, dtype, p_detect=None) -> None:
        self.model = model
        self.xy = xy
        self.velocity_xy = velocity_xy  # None without the Doppler term
        # Every position moves at the robot's speed (only the heading differs).
        self.speed_mps = 0.0
        if velocity_xy is not None and len(velocity_xy):
            self.speed_mps = float(np.hypot(*velocity_xy[0]))
        self.dtype = dtype
        self.expected: list[np.ndarray] | None = None
        self.expected_v: list[np.ndarray] | None = None
        # Per type index: each reflector's best kernel against its own type's distances.
        self.matched: dict[int, np.ndarray] = {}
        self.extra = self.extra_v = None
        self._p_detect: np.ndarray | None = p_detect
        if map_returns is not None:  # (ranges, rates), rates given iff velocity_xy is
            self.extra = map_returns[0].astype(dtype, copy=False)
            if map_returns[1] is not None:
                self.extra_v = map_returns[1].astype(dtype, copy=False)

    def p_detect(self) -> np.ndarray:
        """The radar's detection probability of each reflector (M, N), layout order (needs
        the model's ``visibility``)."""
        if self._p_detect is None:
            self._p_detect = self.model.reflectors.detection_probabilities(self.xy)
        return self._p_detect

    def expected_of(self, t: int) -> tuple[np.ndarray, np.ndarray | None]:
        if self.expected is None:
            if self.velocity_xy is not None:
                self.expected, self.expected_v = self.model.reflectors.expected_with_velocity(
                    self.xy, self.velocity_xy, self.dtype, self._visible_p()
                )
            else:
                self.expected = self.model.reflectors.expected(
                    self.xy, self.dtype, self._visible_p()
                )
        return self.expected[t], None if self.expected_v is None else self.expected_v[t]

    def _visible_p(self) -> np.ndarray | None:
        return None if self.model.visibility is None else self.p_detect()

    def map_returns(self) -> tuple[np.ndarray, np.ndarray | None]:
        if self.extra is None:
            self.extra, self.extra_v = self.model.map_returns.ranges(
                self.xy, self.velocity_xy, self.dtype
            )
        return self.extra, self.extra_v


def log_likelihood_terms(
    model: FingerprintModel,
    xy: np.ndarray,
    segments: list[Segment],
    velocity_xy: np.ndarray | None,
    map_returns: tuple[np.ndarray, np.ndarray | None] | None,
    dtype,
    expected: list[np.ndarray] | None = None,
    p_detect: np.ndarray | None = None,
) -> np.ndarray:
    """Log-likelihood (N,) of the ``segments`` of a fingerprint at positions ``xy`` (N, 2);
    ``velocity_xy`` is None unless the Doppler term applies. ``map_returns``, if given, are
    the map's predicted ranges (K, N) at ``xy`` and, iff ``velocity_xy`` is given, their
    radial velocities; ``expected``, if given, the reflectors' sorted ranges at ``xy`` (the
    Doppler term aside); ``p_detect``, if given, the reflectors' detection probabilities at
    ``xy``."""
    frame = _Frame(model, xy, velocity_xy, map_returns, dtype, p_detect)
    frame.expected = expected
    out = np.zeros(xy.shape[0])
    for seg in segments:
        out += _segment_term(frame, seg)
    if model.detection_probability > 0.0 and model.clutter_probability > 0.0:
        if model.visibility is None:
            out += _missed_term(frame, segments)
        else:
            out += _missed_term_per_reflector(frame, segments)
    return out


def _segment_term(frame: _Frame, seg: Segment) -> np.ndarray:
    """Log-likelihood (N,) of the sorted distances of one type."""
    model, dtype = frame.model, frame.dtype
    c = model.clutter_probability
    e, e_v = frame.expected_of(seg.type_index)  # (m, N), sorted along axis 0
    m = e.shape[0]
    n = len(seg.z)
    dens_v = None
    if e_v is not None and seg.v is not None:
        dens_v = doppler_density(seg.v, e_v, model.doppler_coefficients(), dtype)
    half_inv = (-0.5 / seg.s2).astype(dtype)[:, None]
    log_norm = -0.5 * np.log(2.0 * np.pi * seg.s2)
    ln_scale = log_norm.astype(dtype)[:, None]
    # r[i, j] = half_inv_i (e_j - z_i)^2 for every measured i and expected j.
    r = e[None, :, :] - seg.z.astype(dtype)[:, None, None]  # (n, m, N)
    r *= r
    r *= half_inv[:, :, None]
    # Reflectors each position sees (hidden ones sort last); None: all m everywhere.
    m_seen = model.reflectors.visible_counts(e)
    log_sorted = _sorted_assignment(r, m, m_seen, ln_scale, dens_v)
    counts_match = None if m_seen is None else m_seen == n
    if c == 0.0:
        if log_sorted is not None and counts_match is None:
            return log_sorted
        # No clutter floor: the mixture in the log domain.
        seen = m if m_seen is None else np.maximum(m_seen, 1)
        mix = np.logaddexp.reduce(r, axis=1) + ln_scale - np.log(seen).astype(dtype)
        mix = mix.sum(axis=0, dtype=np.float64)
        return mix if log_sorted is None else np.where(counts_match, log_sorted, mix)
    np.exp(r, out=r)
    if model.detection_probability > 0.0 and model.visibility is None:  # for _missed_term
        frame.matched[seg.type_index] = r.max(axis=0)
    if dens_v is not None:
        r *= dens_v
    g = r.mean(axis=1)  # (n, N); a hidden reflector's kernel is 0
    if model.map_returns is not None:
        _add_map_returns(frame, seg, g, half_inv[:, 0])
    clutter = model.clutter_density_for(
        dens_v is not None, frame.speed_mps, seg.v if dens_v is not None else None
    )
    log_mix = _log_mixture(g, log_norm, c, clutter, dtype)
    p_clean = model.clean_probability
    if m_seen is not None:
        # A position that sees fewer reflectors expects fewer reflector returns and as many
        # clutter and room returns: 1 - r (m - m_seen) / m of the returns expected with all
        # m seen remain (r the reflectors' share then), and every source's share of a
        # distance is divided by that (with c = 0 above: the mean over the seen ones).
        seen_share = 1.0 - p_clean * (m - m_seen) / m
        log_mix -= n * np.log(seen_share)
        p_clean = p_clean * (m_seen / m) / seen_share
    if log_sorted is None:
        return log_mix
    # All n distances are reflectors with probability (1 - c)^n: sorted assignment;
    # otherwise at least one is clutter (and one reflector missed): the mixture.
    p_clean = p_clean**n
    with np.errstate(divide="ignore"):
        both = np.logaddexp(np.log(p_clean) + log_sorted, np.log1p(-p_clean) + log_mix)
    return both if counts_match is None else np.where(counts_match, both, log_mix)


def _sorted_assignment(
    r: np.ndarray, m: int, m_seen: np.ndarray | None, ln_scale: np.ndarray, dens_v
) -> np.ndarray | None:
    """Log-likelihood (N,) of the sorted-to-sorted assignment (e and z both ascending: the
    diagonal of ``r`` (n, m, N)) of the n measured distances to the n nearest reflectors;
    None where it cannot apply (n != m, or with hidden reflectors n > m). With hidden
    reflectors it holds only where exactly n are seen (the caller masks the rest)."""
    n = r.shape[0]
    if not (n == m or (m_seen is not None and n < m)):
        return None
    diag = r[np.arange(n), np.arange(n)]
    diag += ln_scale
    if dens_v is not None:
        diag += np.log(dens_v[np.arange(n), np.arange(n)])
    return diag.sum(axis=0, dtype=np.float64)


def _add_map_returns(frame: _Frame, seg: Segment, g: np.ndarray, half_inv: np.ndarray) -> None:
    """Mix the map's predicted returns into the reflector densities ``g`` (n, N), in place."""
    model = frame.model
    extra, extra_v = frame.map_returns()
    g *= frame.dtype(1.0 - model.map_returns.probability)
    g += map_return_density(
        seg.z,
        half_inv,
        extra,
        model.map_returns.weights,
        seg.v,
        extra_v,
        model.doppler_coefficients(),
        model.use_numba,
    )


def _missed_term(frame: _Frame, segments: list[Segment]) -> np.ndarray:
    """Negative information (N,): a reflector that no measured distance matches was missed,
    which a pose that predicts it visible explains with ``1 - P_D`` only.

    A reflector counts as matched by a distance of *any* type (``exp(-r^2 / (2 s^2))`` of its
    best match): a weak return's RCS estimate often falls in another type's window, and a
    per-type match would then hold the miss against the true pose on every such frame (the
    2 + 2 layout's small reflector; the reflector monitor pools the types for the same
    reason). Types without reflectors in the layout are skipped.
    """
    model, dtype = frame.model, frame.dtype
    out = np.zeros(frame.xy.shape[0])
    p_d = dtype(model.detection_probability)
    for t, count in enumerate(model.counts):
        if count == 0:
            continue
        e = frame.expected_of(t)[0]  # (m, N)
        matched = frame.matched.get(t)  # the segment's own kernel, kept by _segment_term
        matched = _best_kernels(e, segments, dtype, matched, t if matched is not None else None)
        if matched is None:  # no distance at all: every reflector of the type missed
            out += count * np.log1p(-float(p_d))
            continue
        matched *= p_d
        matched += dtype(1.0) - p_d
        out += np.log(matched).sum(axis=0, dtype=np.float64)
    return out


def _best_kernels(
    e: np.ndarray,
    segments: list[Segment],
    dtype,
    matched: np.ndarray | None = None,
    skip_type: int | None = None,
) -> np.ndarray | None:
    """Each reflector's largest kernel ``exp(-r^2 / (2 s^2))`` (m, N) against the distances
    of every segment (of any type) but the one of ``skip_type``, from its ranges ``e`` (m, N),
    folded into ``matched`` (in place); None when there is no distance at all."""
    for seg in segments:
        if seg.type_index == skip_type:
            continue
        r = e[None, :, :] - seg.z.astype(dtype)[:, None, None]
        r *= r
        r *= (-0.5 / seg.s2).astype(dtype)[:, None, None]
        best = np.exp(r.max(axis=0))  # exp is monotone: the largest kernel
        matched = best if matched is None else np.maximum(matched, best, out=matched)
    return matched


def _missed_term_per_reflector(frame: _Frame, segments: list[Segment]) -> np.ndarray:
    """:func:`_missed_term` with each reflector's own detection probability at each
    position, ``P_D p_j`` (``p_j`` from the model's ``visibility``: 0 for a hidden reflector,
    whose silence then costs nothing). The best matches are taken over the reflectors in
    layout order, as the probabilities are."""
    model, dtype = frame.model, frame.dtype
    out = np.zeros(frame.xy.shape[0])
    p = frame.p_detect().astype(dtype) * dtype(model.detection_probability)  # (M, N)
    ranges = model.reflectors.ranges(frame.xy, dtype)
    for t, count in enumerate(model.counts):
        if count == 0:
            continue
        p_t = p[model.reflectors.type_rows[t]]  # (m, N)
        best = _best_kernels(ranges[t], segments, dtype)
        if best is None:  # no distance at all
            best = np.zeros_like(p_t)
        # log(p k + 1 - p) = log1p(-p (1 - k))
        best -= dtype(1.0)
        best *= p_t
        out += np.log1p(best).sum(axis=0, dtype=np.float64)
    return out


def _log_mixture(
    g: np.ndarray, log_norm: np.ndarray, c: float, clutter_density: float | np.ndarray, dtype
):
    """``sum_i log((1 - c) N_i g_i + c rho_i)`` (N,) over the distances' mixture densities
    ``g`` (n, N) (normalisation ``N_i = exp(log_norm_i)``), ``rho`` the clutter density, one
    for all distances or one per distance (n,) (its velocity's)."""
    g *= ((1.0 - c) * np.exp(log_norm)).astype(dtype)[:, None]
    rho = np.asarray(clutter_density, dtype=float)
    g += (c * rho).astype(dtype)[:, None] if rho.ndim else dtype(c * rho)
    # Every factor is >= the clutter floor: chunks of 8 cannot underflow in float32.
    log_mix = np.zeros(g.shape[1])
    for k in range(0, g.shape[0], 8):
        log_mix += np.log(np.prod(g[k : k + 8], axis=0))
    return log_mix
