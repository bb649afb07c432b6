"""Two returns in one range cell: the detections model's merged peak follows the signal chain.

The carrier phase between the two decides where their sum peaks (in phase: between them; out
of phase: pushed away from the weaker one). A power-weighted centroid ignores it, so its error
stays put while the robot moves the few millimetres that turn the phases round.
"""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.radar.paths import Paths
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world import World

PHASES = np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False)


def _peaks(paper_cfg, sep_bins: float, ratio: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Offsets (bins) of the detection nearest the stronger return, signal chain and
    detections model, over ``PHASES``; and the power centroid's offset."""
    world = World.from_config(paper_cfg)
    radar = paper_cfg.radar
    sig = RadarSensor(world, radar.model_copy(update={"fidelity": "signal", "noise": False}))
    fast = RadarSensor(world, radar.model_copy(update={"fidelity": "detections", "noise": False}))
    res = sig.fmcw.range_resolution_m
    r1 = 40.25 * res
    peak = sig.noise_cell * 1e4 / sig.processor.coherent_gain2  # 40 dB: no noise needed
    rng = np.random.default_rng(0)
    out = []
    for dphi in PHASES:
        paths = Paths(
            np.array([r1, r1 + sep_bins * res]),
            np.array([0.5, 0.5]),
            np.array([peak, peak * ratio]),
            np.array([0.0, dphi]),
            np.array([-2, -2]),
            np.array([0, 0]),
            np.array([4, 4]),
        )
        row = []
        for det in (sig.process(paths, rng), fast._fast.detect(paths, rng)):
            row.append((det.range_m[np.argmin(np.abs(det.range_m - r1))] - r1) / res)
        out.append(row)
    o = np.array(out)
    return o[:, 0], o[:, 1], ratio * sep_bins / (1.0 + ratio)


@pytest.mark.parametrize("sep_bins", [0.3, 0.6])
def test_the_merged_peak_moves_with_the_phase_as_the_signal_chains_does(paper_cfg, sep_bins):
    signal, model, power_centroid = _peaks(paper_cfg, sep_bins, ratio=0.5)
    assert np.ptp(signal) > 0.3  # the phase matters in the real chain ...
    assert np.ptp(model) > 0.3  # ... and in the model
    err_model = np.mean(np.abs(model - signal))
    err_power = np.mean(np.abs(power_centroid - signal))
    assert err_model < 0.1, (signal, model)
    assert err_model < 0.5 * err_power, (err_model, err_power)


def test_one_return_peaks_where_it_is(paper_cfg):
    signal, model, _ = _peaks(paper_cfg, 0.0, ratio=1e-12)
    assert np.all(np.abs(model) < 1e-9)
    assert np.all(np.abs(signal) < 0.05)
