"""Detections-level radar model: detections drawn straight from the channel's paths.

For fast RL. It mimics the signal model (:mod:`lrp_gym.radar.processing`) without building the
cube or the map:

1. each path lands at a fractional (range, Doppler) bin, including the range-Doppler coupling;
2. paths within one resolution cell of the window (``WindowTable.resolution_bins``) of a
   stronger path merge into it: the position is the power-weighted centroid, the amplitude
   the coherent sum (carrier phases included, each path weighted by the window's response at
   its distance from the head), so close paths fade as they do in the map;
3. the peak is that power times the scalloping loss of a uniformly drawn sub-bin offset, plus
   complex Gaussian noise of one map cell;
4. OS-CFAR with interference: a peak at level ``P`` is masked when more than ``N - k`` of its
   training cells lie above ``P / alpha``. The cells each peak (the tested one included)
   raises above that level are the rectangle where the window's sidelobe envelope, times the
   peak's power, exceeds it; the model counts the overlap of these rectangles with the
   training ring. Otherwise the threshold is ``alpha`` times the mean k-th order statistic
   of the noise. CA/SO/GO use the same rule with ``k = N / 2`` (masking by a few strong cells
   is what tells OS from the averaging detectors; the averaging ones are masked earlier,
   which this model does not reproduce);
5. the interpolation error is Gaussian with std ``K / sqrt(2 SNR)`` bins per axis, ``K``
   fitted against the signal model by :mod:`lrp_gym.radar.calibrate`;
6. noise false alarms: a Poisson number (``Pfa`` per cell) at random cells.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from lrp_gym.radar._merge import greedy_owner
from lrp_gym.radar.detections import Detections
from lrp_gym.radar.paths import Paths
from lrp_gym.radar.processing import window, window_dtft

if TYPE_CHECKING:
    # The sensor builds this model for itself (detections fidelity), so it imports this module.
    from lrp_gym.radar.sensor import RadarSensor

#: interpolation error std in bins times sqrt(2 SNR); from ``python -m lrp_gym.radar.calibrate``
RANGE_ERROR_K = 1.02
DOPPLER_ERROR_K = 1.08


def sidelobe_envelope(name: str, n: int, max_bins: float, step: float = 0.05) -> np.ndarray:
    """Decreasing envelope of ``|W(d)|^2 / |W(0)|^2`` on offsets ``0, step, ..., max_bins``."""
    w = window(name, n)
    d = np.arange(0.0, max_bins + step, step)
    g = np.abs(window_dtft(w, d)) ** 2 / float(w.sum()) ** 2
    return np.maximum.accumulate(g[::-1])[::-1]


def cfar_noise_statistic(cfar) -> float:
    """The mean of the CFAR's noise estimate for a noise-only ring, in units of one cell's
    noise power: the k-th order statistic of ``N`` exponential cells (OS), half the ring's
    cells (SO, GO: they sum a half), 1 (CA: a mean)."""
    n = cfar.n_training
    if cfar.method == "OS":
        return float(np.sum(1.0 / (n - np.arange(cfar.rank))))  # E[X_(k)], unit noise
    if cfar.method in ("SO", "GO"):
        return float(cfar.n_half)
    return 1.0


def cfar_threshold_w(sensor: RadarSensor) -> float:
    """The map level a peak must exceed to be detected: ``alpha`` times the CFAR's mean noise
    estimate (without noise: the level a noise-only cell would exceed with probability Pfa)."""
    if not sensor.noise_on:
        return -math.log(sensor.cfar.pfa) * sensor.noise_cell
    return sensor.cfar.alpha * cfar_noise_statistic(sensor.cfar) * sensor.noise_cell


class FastDetectionModel:
    """Detections straight from paths; build with :meth:`for_sensor`."""

    def __init__(self, sensor: RadarSensor) -> None:
        self.sensor = sensor
        fm, proc, cfar = sensor.fmcw, sensor.processor, sensor.cfar
        self.ns, self.nc = fm.samples_per_chirp, fm.chirps_per_frame
        name = sensor.config.window
        self.step = 0.05
        (h0, h1) = cfar.half_window
        self.env_r = sidelobe_envelope(name, self.ns, h0 + 2.0, self.step)
        self.env_d = sidelobe_envelope(name, self.nc, h1 + 2.0, self.step)
        self.res_r = proc.range_table.resolution_bins
        self.res_d = proc.doppler_table.resolution_bins
        n = cfar.n_training
        k = cfar.rank if cfar.method == "OS" else max(n // 2, 1)
        self.max_occupied = n - k
        self.alpha = cfar.alpha

    @classmethod
    def for_sensor(cls, sensor: RadarSensor) -> FastDetectionModel:
        return cls(sensor)

    def _extent(self, env: np.ndarray, ratio: np.ndarray) -> np.ndarray:
        """Offset (bins) out to which ``env`` stays above ``ratio`` (0 if never)."""
        # env decreases: count the table entries above the ratio
        idx = np.searchsorted(-env, -ratio, side="left")
        return idx * self.step

    def detect(self, paths: Paths, rng: np.random.Generator) -> Detections:
        """Detections of one frame from its paths (steps 1-6 of the module docstring)."""
        s = self.sensor
        fm, cell = s.fmcw, s.noise_cell
        crb, cdb, cpk = self._merge(paths)
        g, clean, meas = self._peaks(cpk, rng)
        thr = self._threshold()
        det = (meas > thr) & ~self._masked(meas, clean, crb, cdb)
        rng_m, vel = self._positions(crb[det], cdb[det], clean[det], rng)
        power_w = meas[det] / (s.processor.coherent_gain2 * g[det] ** 2)
        snr_db = 10.0 * np.log10(meas[det] / cell)
        if s.noise_on:
            rng_m, vel, snr_db, power_w = self._false_alarms(rng_m, vel, snr_db, power_w, thr, rng)
        keep = (rng_m >= s.min_range_m) & (rng_m <= fm.max_range_m)
        power_w = power_w[keep]
        return Detections(
            range_m=rng_m[keep],
            velocity_mps=vel[keep],
            power_dbm=10.0 * np.log10(power_w) + 30.0,
            rcs_dbsm=s.rcs_dbsm(power_w, rng_m[keep]),
            snr_db=snr_db[keep],
        )

    def _merge(self, paths: Paths) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Steps 1-2: each merged peak's range and Doppler bin (H,) and its coherent power.

        Paths within one resolution cell of a stronger one (greedy by power) merge into it:
        power-weighted centroid, coherent sum weighted by the window response at the offset.
        """
        fm, proc, nc = self.sensor.fmcw, self.sensor.processor, self.nc
        coupling = 2.0 * paths.velocity_mps * fm.chirp_period_s / fm.wavelength_m
        order = np.argsort(-paths.power_w)
        rb = (paths.range_m / fm.range_resolution_m + coupling)[order]
        db = (paths.velocity_mps / fm.velocity_resolution_mps)[order]  # from 0 velocity
        peak = paths.power_w[order] * proc.coherent_gain2
        phase = paths.phase_rad[order]
        owner = greedy_owner(rb, db, self.res_r, self.res_d, nc)
        n = len(rb)
        heads = np.flatnonzero(owner == np.arange(n))
        rel_r = rb - rb[owner]
        rel_d = (db - db[owner] + nc / 2) % nc - nc / 2  # Doppler relative to the head
        # coherent sum, each path weighted by the window response at its offset from the head
        resp = np.sqrt(
            np.interp(np.abs(rel_r), np.arange(len(self.env_r)) * self.step, self.env_r)
            * np.interp(np.abs(rel_d), np.arange(len(self.env_d)) * self.step, self.env_d)
        )
        # The beat signal starts at sample 0, so a path's response at an offset of d bins
        # from its own peak carries a linear phase pi d (N - 1) / N (per axis).
        lin = np.pi * (rel_r * (self.ns - 1) / self.ns + rel_d * (nc - 1) / nc)
        z = np.sqrt(peak) * resp * np.exp(1j * (phase + lin))
        amp = np.bincount(owner, weights=z.real, minlength=n) + 1j * np.bincount(
            owner, weights=z.imag, minlength=n
        )
        # The peak of |sum z_i W(x - x_i)|^2, to first order in the main lobe's curvature, is
        # the centroid with weights Re(conj(A) z_i) / |A|^2: in phase the paths pull the peak
        # together, out of phase one pushes it away. A power centroid ignores the carrier
        # phase, so its error would stay put over the many frames a few mm of motion turns
        # the phases through (the signal chain's errors decorrelate within a few cm).
        a = amp[owner]
        w = (a.real * z.real + a.imag * z.imag) / np.maximum(np.abs(a) ** 2, 1e-300)
        # near-cancellation makes the weights large: the peak stays within a cell of the head
        shift_r = np.bincount(owner, weights=w * rel_r, minlength=n)[heads]
        shift_d = np.bincount(owner, weights=w * rel_d, minlength=n)[heads]
        crb = rb[heads] + np.clip(shift_r, -self.res_r, self.res_r)
        cdb = db[heads] + np.clip(shift_d, -self.res_d, self.res_d)
        return crb, cdb, np.abs(amp[heads]) ** 2

    def _peaks(
        self, cpk: np.ndarray, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Step 3: scalloping amplitude gain at a random sub-bin offset, the clean peak power
        and the measured one (plus complex Gaussian noise of one map cell when noise is on)."""
        proc, nh = self.sensor.processor, len(cpk)
        g = np.interp(
            rng.uniform(-0.5, 0.5, nh), proc.range_table.offset, proc.range_table.gain
        ) * np.interp(
            rng.uniform(-0.5, 0.5, nh), proc.doppler_table.offset, proc.doppler_table.gain
        )
        clean = cpk * g**2
        if not self.sensor.noise_on:
            return g, clean, clean
        zn = rng.standard_normal(nh) + 1j * rng.standard_normal(nh)
        meas = np.abs(np.sqrt(clean) + np.sqrt(self.sensor.noise_cell / 2.0) * zn) ** 2
        return g, clean, meas

    def _masked(
        self, meas: np.ndarray, clean: np.ndarray, crb: np.ndarray, cdb: np.ndarray
    ) -> np.ndarray:
        """Step 4: peaks (H,) whose CFAR training ring has too many cells raised above
        ``meas / alpha`` by the sidelobes of any peak (itself included)."""
        cfar, nc = self.sensor.cfar, self.nc
        level = meas / self.alpha  # (H,)
        ratio = level[:, None] / np.maximum(clean[None, :], 1e-300)  # (i, j)
        ext_r = self._extent(self.env_r, ratio)
        ext_d = self._extent(self.env_d, ratio)
        ri, ki = np.round(crb), np.round(cdb)
        rel_r = crb[None, :] - ri[:, None]
        rel_k = (cdb[None, :] - ki[:, None] + nc / 2) % nc - nc / 2
        (g0, g1), (h0, h1) = cfar.guard, cfar.half_window
        occupied = _overlap(rel_r, ext_r, h0) * _overlap(rel_k, ext_d, h1) - _overlap(
            rel_r, ext_r, g0
        ) * _overlap(rel_k, ext_d, g1)
        return occupied.sum(axis=1) > self.max_occupied

    def _threshold(self) -> float:
        """Step 4: the detection threshold (:func:`cfar_threshold_w`)."""
        return cfar_threshold_w(self.sensor)

    def _positions(
        self, crb: np.ndarray, cdb: np.ndarray, clean: np.ndarray, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        """Step 5: range (m) and folded velocity (m/s) of the detected peaks, with the fitted
        interpolation error when noise is on and the range-Doppler coupling removed."""
        s = self.sensor
        fm = s.fmcw
        snr = clean / s.noise_cell
        n = len(crb)
        sig = 1.0 / np.sqrt(np.maximum(2.0 * snr, 1e-12))
        err_r = rng.standard_normal(n) * RANGE_ERROR_K * sig if s.noise_on else np.zeros(n)
        err_d = rng.standard_normal(n) * DOPPLER_ERROR_K * sig if s.noise_on else np.zeros(n)
        vel = (cdb + err_d) * fm.velocity_resolution_mps
        vmax = fm.max_velocity_mps
        vel = (vel + vmax) % (2.0 * vmax) - vmax
        rng_bins = crb + err_r - 2.0 * vel * fm.chirp_period_s / fm.wavelength_m
        return rng_bins * fm.range_resolution_m, vel

    def _false_alarms(
        self,
        rng_m: np.ndarray,
        vel: np.ndarray,
        snr_db: np.ndarray,
        power_w: np.ndarray,
        thr: float,
        rng: np.random.Generator,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Step 6: append a Poisson number (Pfa per cell) of noise detections at random cells."""
        fm, cfar, cell = self.sensor.fmcw, self.sensor.cfar, self.sensor.noise_cell
        vmax = fm.max_velocity_mps
        n_fa = rng.poisson(cfar.pfa * self.ns * self.nc)
        if not n_fa:
            return rng_m, vel, snr_db, power_w
        fa_r = rng.uniform(1, self.ns - 1, n_fa)
        fa_v = rng.uniform(-vmax, vmax, n_fa)
        fa_p = thr * (1.0 + rng.exponential(1.0 / self.alpha, n_fa))
        return (
            np.concatenate([rng_m, fa_r * fm.range_resolution_m]),
            np.concatenate([vel, fa_v]),
            np.concatenate([snr_db, 10.0 * np.log10(fa_p / cell)]),
            np.concatenate([power_w, fa_p / self.sensor.processor.coherent_gain2]),
        )


def _overlap(rel: np.ndarray, ext: np.ndarray, half: int) -> np.ndarray:
    """Integers in [-half, half] strictly within ext of rel."""
    lo = np.maximum(np.floor(rel - ext) + 1, -half)
    hi = np.minimum(np.ceil(rel + ext) - 1, half)
    return np.where(ext > 0, np.maximum(hi - lo + 1, 0), 0)
