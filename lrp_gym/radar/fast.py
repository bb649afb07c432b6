"""Detections-level radar model: detections drawn straight from the channel's paths.

For fast RL. It mimics the signal model (:mod:`lrp_gym.radar.processing`) without building the
cube:

1. each path lands at a fractional (range, Doppler) bin, including the range-Doppler coupling;
2. paths within one resolution cell of the window (see ``WindowTable.resolution_bins``) of a
   stronger path merge into it: position is the power-weighted centroid, power the sum;
3. the peak in the map is ``P * coherent_gain^2 * scalloping^2`` at a uniformly drawn sub-bin
   offset, plus complex Gaussian noise of one map cell;
4. CA-CFAR with interference: a peak is detected when it exceeds
   ``alpha / N * (N * noise + E * sum of the peaks inside its training ring)``, where ``E`` is
   the window's energy spread (Parseval: ``N sum w^2 / (sum w)^2`` per axis), so strong returns
   nearby mask weak ones as they do in the map (the SO/GO/OS variants are approximated by CA);
5. the interpolation error is Gaussian with std ``k / sqrt(SNR)`` bins per axis, ``k``
   calibrated against the signal model (:data:`RANGE_ERROR_K`, :data:`DOPPLER_ERROR_K`);
6. noise false alarms: a Poisson number (``Pfa`` per cell) at random cells.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lrp_gym.radar.channel import Paths
from lrp_gym.radar.detections import Detections

#: interpolation error std in bins at unit SNR (times 1/sqrt(SNR)); fitted to the signal model
RANGE_ERROR_K = 0.6
DOPPLER_ERROR_K = 0.6


@dataclass
class FastDetectionModel:
    """Detections straight from paths; build with :meth:`for_sensor`."""

    sensor: object  # RadarSensor (kept untyped to avoid an import cycle)

    @classmethod
    def for_sensor(cls, sensor) -> FastDetectionModel:
        return cls(sensor)

    def detect(self, paths: Paths, rng: np.random.Generator) -> Detections:
        s = self.sensor
        fm, proc, cfar = s.fmcw, s.processor, s.cfar
        ns, nc = fm.samples_per_chirp, fm.chirps_per_frame
        noise_on = s.noise_on
        cell = s.noise_cell
        coupling = 2.0 * paths.velocity_mps * fm.chirp_period_s / fm.wavelength_m
        rb = paths.range_m / fm.range_resolution_m + coupling
        db = paths.velocity_mps / fm.velocity_resolution_mps  # Doppler bins from 0 velocity
        peak = paths.power_w * proc.coherent_gain2
        # --- merge paths within one resolution cell of a stronger one (greedy by power)
        order = np.argsort(-peak)
        rb, db, peak = rb[order], db[order], peak[order]
        res_r, res_d = proc.range_table.resolution_bins, proc.doppler_table.resolution_bins
        dr = np.abs(rb[:, None] - rb[None, :])
        dd = np.abs((db[:, None] - db[None, :] + nc / 2) % nc - nc / 2)
        near = (dr < res_r) & (dd < res_d)
        owner = np.full(len(rb), -1)
        for i in range(len(rb)):  # loop over paths (tens), not samples
            if owner[i] < 0:
                owner[(owner < 0) & near[i]] = i
        heads = np.unique(owner)
        wsum = np.bincount(owner, weights=peak, minlength=len(rb))[heads]
        crb = np.bincount(owner, weights=peak * rb, minlength=len(rb))[heads] / wsum
        cdb = (
            db[heads]
            + np.bincount(
                owner, weights=peak * ((db - db[owner] + nc / 2) % nc - nc / 2), minlength=len(rb)
            )[heads]
            / wsum
        )
        cpk = wsum
        # --- scalloping at a random sub-bin offset, noise on the peak
        off_r = rng.uniform(-0.5, 0.5, len(heads))
        off_d = rng.uniform(-0.5, 0.5, len(heads))
        g = np.interp(off_r, proc.range_table.offset, proc.range_table.gain) * np.interp(
            off_d, proc.doppler_table.offset, proc.doppler_table.gain
        )
        clean = cpk * g**2
        if noise_on:
            z = rng.standard_normal(len(heads)) + 1j * rng.standard_normal(len(heads))
            meas = np.abs(np.sqrt(clean) + np.sqrt(cell / 2.0) * z) ** 2
        else:
            meas = clean
        # --- CA-CFAR with the interference of neighbouring peaks
        (g0, g1), (h0, h1) = cfar.guard, cfar.half_window
        ar = np.abs(crb[:, None] - crb[None, :])
        ad = np.abs((cdb[:, None] - cdb[None, :] + nc / 2) % nc - nc / 2)
        in_ring = (ar <= h0 + 0.5) & (ad <= h1 + 0.5) & ~((ar <= g0 + 0.5) & (ad <= g1 + 0.5))
        spread = (ns * proc.range_table.noise_gain / proc.range_table.coherent_gain**2) * (
            nc * proc.doppler_table.noise_gain / proc.doppler_table.coherent_gain**2
        )
        interference = spread * (in_ring * clean[None, :]).sum(axis=1)
        n_tr = cfar.n_training
        alpha_ca = n_tr * (cfar.pfa ** (-1.0 / n_tr) - 1.0)
        thr = alpha_ca / n_tr * ((n_tr * cell if noise_on else 0.0) + interference)
        if not noise_on:
            thr = np.maximum(thr, -math.log(cfar.pfa) * cell)
        det = meas > thr
        snr = clean[det] / cell
        n = int(det.sum())
        sig = 1.0 / np.sqrt(np.maximum(2.0 * snr, 1e-12))
        err_r = rng.standard_normal(n) * RANGE_ERROR_K * sig if noise_on else np.zeros(n)
        err_d = rng.standard_normal(n) * DOPPLER_ERROR_K * sig if noise_on else np.zeros(n)
        vel = (cdb[det] + err_d) * fm.velocity_resolution_mps
        vmax = fm.max_velocity_mps
        vel = (vel + vmax) % (2.0 * vmax) - vmax
        rng_bins = crb[det] + err_r - 2.0 * vel * fm.chirp_period_s / fm.wavelength_m
        rng_m = rng_bins * fm.range_resolution_m
        power_w = meas[det] / (proc.coherent_gain2 * g[det] ** 2)
        snr_db = 10.0 * np.log10(meas[det] / cell)
        # --- noise false alarms
        if noise_on:
            n_fa = rng.poisson(cfar.pfa * ns * nc)
            if n_fa:
                fa_r = rng.uniform(1, ns - 1, n_fa)
                fa_v = rng.uniform(-vmax, vmax, n_fa)
                fa_p = cell * (-math.log(cfar.pfa) + rng.exponential(1.0, n_fa))
                rng_m = np.concatenate([rng_m, fa_r * fm.range_resolution_m])
                vel = np.concatenate([vel, fa_v])
                snr_db = np.concatenate([snr_db, 10.0 * np.log10(fa_p / cell)])
                power_w = np.concatenate([power_w, fa_p / proc.coherent_gain2])
        keep = (rng_m >= s.min_range_m) & (rng_m <= fm.max_range_m)
        power_w = power_w[keep]
        return Detections(
            range_m=rng_m[keep],
            velocity_mps=vel[keep],
            power_dbm=10.0 * np.log10(power_w) + 30.0,
            rcs_dbsm=s.rcs_dbsm(power_w, rng_m[keep]),
            snr_db=snr_db[keep],
        )
