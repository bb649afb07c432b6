"""Fit the detections-level model's constants against the signal model (rerunnable sweep).

``python -m lrp_gym.radar.calibrate`` places single targets at random sub-bin positions in
noise, at a sweep of peak SNRs (clean peak power over one cell's noise, the SNR the fast model
uses), runs the signal chain (cube, FFT, CFAR, interpolation) and fits the interpolation error
``std(error_bins) = K / sqrt(2 SNR)`` per axis. It prints the fitted constants (commit them to
:mod:`lrp_gym.radar.detection_model`) and, per SNR, the detection probability of both fidelities.
"""

from __future__ import annotations

import numpy as np

from lrp_gym.config import ScenarioConfig, load_scenario
from lrp_gym.radar.paths import Paths
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world.world import World


def _single_path(sensor, snr_db: float, rng: np.random.Generator) -> tuple[Paths, float, float]:
    fm = sensor.fmcw
    rbin = rng.uniform(20.0, fm.samples_per_chirp - 20.0)
    vel = rng.uniform(-0.8, 0.8) * fm.max_velocity_mps
    peak = sensor.noise_cell * 10.0 ** (snr_db / 10.0)
    p = Paths(
        np.array([rbin * fm.range_resolution_m]),
        np.array([vel]),
        np.array([peak / sensor.processor.coherent_gain2]),
        np.array([rng.uniform(0, 2 * np.pi)]),
        np.array([-2]),
        np.array([0]),
        np.array([4]),
    )
    return p, rbin * fm.range_resolution_m, vel


def sweep(
    cfg: ScenarioConfig | None = None,
    snrs_db: tuple[float, ...] = (13.0, 16.0, 20.0, 25.0, 30.0, 40.0),
    trials: int = 300,
    seed: int = 0,
) -> dict:
    """Run the sweep; returns per-SNR error std (bins), detection rates and the fitted K."""
    cfg = cfg or load_scenario("ipin2023")
    world = World.from_config(cfg)  # only its waveform is used: the paths are synthetic
    sig = RadarSensor(world, cfg.radar.model_copy(update={"fidelity": "signal", "noise": True}))
    fast = RadarSensor(
        world, cfg.radar.model_copy(update={"fidelity": "detections", "noise": True})
    )
    fast_model = fast._fast
    if fast_model is None:  # the detections fidelity always builds it
        raise RuntimeError("the detections-fidelity sensor has no fast model")
    fm = sig.fmcw
    rng = np.random.default_rng(seed)
    rows = []
    for snr_db in snrs_db:
        er, ed, hit_s, hit_f = [], [], 0, 0
        for _ in range(trials):
            p, r, v = _single_path(sig, snr_db, rng)
            det = sig.process(p, rng)
            close = np.abs(det.range_m - r) < 2 * fm.range_resolution_m
            if close.any():
                j = np.flatnonzero(close)[np.argmin(np.abs(det.range_m[close] - r))]
                hit_s += 1
                er.append((det.range_m[j] - r) / fm.range_resolution_m)
                ed.append((det.velocity_mps[j] - v) / fm.velocity_resolution_mps)
            dfast = fast_model.detect(p, rng)
            hit_f += bool(np.any(np.abs(dfast.range_m - r) < 2 * fm.range_resolution_m))
        snr = 10.0 ** (snr_db / 10.0)
        rows.append(
            {
                "snr_db": snr_db,
                "range_std_bins": float(np.std(er)),
                "doppler_std_bins": float(np.std(ed)),
                "k_range": float(np.std(er) * np.sqrt(2 * snr)),
                "k_doppler": float(np.std(ed) * np.sqrt(2 * snr)),
                "pd_signal": hit_s / trials,
                "pd_detections": hit_f / trials,
            }
        )
    good = [r for r in rows if r["pd_signal"] > 0.9]
    return {
        "rows": rows,
        "RANGE_ERROR_K": float(np.median([r["k_range"] for r in good])),
        "DOPPLER_ERROR_K": float(np.median([r["k_doppler"] for r in good])),
    }


def main() -> None:
    res = sweep()
    for r in res["rows"]:
        print(
            f"SNR {r['snr_db']:5.1f} dB: range std {r['range_std_bins']:.4f} bins "
            f"(K {r['k_range']:.3f}), Doppler std {r['doppler_std_bins']:.4f} bins "
            f"(K {r['k_doppler']:.3f}), Pd signal {r['pd_signal']:.2f} "
            f"detections {r['pd_detections']:.2f}"
        )
    print(f"RANGE_ERROR_K = {res['RANGE_ERROR_K']:.3f}")
    print(f"DOPPLER_ERROR_K = {res['DOPPLER_ERROR_K']:.3f}")


if __name__ == "__main__":
    main()
