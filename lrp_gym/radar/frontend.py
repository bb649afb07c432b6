"""FMCW front end: link budget, thermal noise and the beat-signal cube of a chirp sequence.

Signal model (complex baseband, one Tx and one Rx antenna). Path ``p`` with received power
``P_p``, range ``R_p``, radial velocity ``v_p`` and carrier phase ``phi_p`` contributes, at
sample ``n`` of chirp ``k``,

    sqrt(P_p) exp(j 2 pi (n / N_s) (R_p / dR + 2 v_p T_c / lambda)
                  + j 2 pi k (2 v_p T_c / lambda) + j phi_p)

so the cube is separable: (samples x paths) @ (paths x chirps). The second term in the range
exponent is the FMCW range-Doppler coupling (the Doppler shift adds to the beat frequency); the
processing removes it with the measured velocity. Not modelled: range migration within a frame
(at 2 m/s it is 1.4 cm, a fifth of a bin), Tx-Rx leakage, phase noise, IF filter roll-off.
Thermal noise is complex white Gaussian of power ``k T f_s F`` per sample (the complex
sample rate is the noise bandwidth).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.constants import Boltzmann

from lrp_gym.waveform import FmcwParameters

#: the range steering vector is built as an outer product of two short tables of this length
_SPLIT = 16
_UNIT_W = 1e-12


def db_to_lin(db: float) -> float:
    return float(10.0 ** (db / 10.0))


def link_constant_w_m2(
    tx_power_dbm: float, tx_gain_dbi: float, rx_gain_dbi: float, wavelength_m: float
) -> float:
    """``P_T G_T G_R lambda^2`` in W m^2, the constant of the radar equation."""
    return (
        db_to_lin(tx_power_dbm)
        * 1e-3
        * db_to_lin(tx_gain_dbi)
        * db_to_lin(rx_gain_dbi)
        * wavelength_m**2
    )


def noise_power_w(fmcw: FmcwParameters, noise_figure_db: float, temperature_k: float) -> float:
    """Thermal noise power per complex sample, ``k T f_s F`` in W."""
    return Boltzmann * temperature_k * fmcw.sample_rate_hz * db_to_lin(noise_figure_db)


def range_steering(bins: np.ndarray, n_samples: int, dtype=np.complex64) -> np.ndarray:
    """``exp(j 2 pi bins n / N)`` for n = 0..N-1, shape (P, N).

    Built as the outer product of two tables of length 16 and N/16 (when N divides), which is
    several times cheaper than one complex exponential per element.
    """
    bins = np.asarray(bins, float)
    w = 2.0 * np.pi * bins / n_samples
    if n_samples % _SPLIT or n_samples < 2 * _SPLIT:
        return np.exp(1j * np.outer(w, np.arange(n_samples))).astype(dtype)
    m = n_samples // _SPLIT
    lo = np.exp(1j * np.outer(w, np.arange(_SPLIT))).astype(dtype)  # (P, 16)
    hi = np.exp(1j * np.outer(w * _SPLIT, np.arange(m))).astype(dtype)  # (P, m)
    return (hi[:, :, None] * lo[:, None, :]).reshape(len(w), n_samples)


def beat_cube(
    fmcw: FmcwParameters,
    range_m: np.ndarray,
    velocity_mps: np.ndarray,
    power_w: np.ndarray,
    phase_rad: np.ndarray,
    *,
    noise_w: float = 0.0,
    rng: np.random.Generator | None = None,
    dtype=np.complex64,
) -> np.ndarray:
    """Beat-signal cube (samples x chirps) of the given paths plus thermal noise.

    Parameters
    ----------
    fmcw : FmcwParameters
    range_m, velocity_mps, power_w, phase_rad : arrays (P,)
        The paths (see :class:`lrp_gym.radar.channel.Paths`).
    noise_w : float
        Noise power per complex sample; 0 for a noise-free cube.
    rng : numpy.random.Generator
        Needed when ``noise_w > 0``.

    Returns
    -------
    ndarray of complex, shape (N_s, N_c)
    """
    ns, nc = fmcw.samples_per_chirp, fmcw.chirps_per_frame
    doppler_cycles = 2.0 * np.asarray(velocity_mps) * fmcw.chirp_period_s / fmcw.wavelength_m
    rbins = np.asarray(range_m) / fmcw.range_resolution_m + doppler_cycles
    s_range = range_steering(rbins, ns, dtype)  # (P, Ns)
    # OpenBLAS' cgemm is ~20x slower on amplitudes of order 1e-7 (sqrt of pW): work in units
    # of sqrt(1 pW) and scale back afterwards.
    amp = np.sqrt(np.asarray(power_w) / _UNIT_W) * np.exp(1j * np.asarray(phase_rad))
    s_dopp = np.exp(1j * (2.0 * np.pi * np.outer(doppler_cycles, np.arange(nc))))
    s_dopp = (amp[:, None] * s_dopp).astype(dtype)  # (P, Nc)
    cube = s_range.T @ s_dopp
    cube *= np.float32(math.sqrt(_UNIT_W))
    if noise_w > 0.0:
        if rng is None:
            raise ValueError("a random generator is needed for noise")
        z = rng.standard_normal((ns, nc, 2), dtype=np.float32)
        z *= np.float32(np.sqrt(noise_w / 2.0))
        cube += z.view(np.complex64)[..., 0]
    return cube
