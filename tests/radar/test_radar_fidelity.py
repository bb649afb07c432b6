"""The detections-level model must keep the signal model's statistics (paper scenario)."""

from __future__ import annotations

import numpy as np

from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world import World


def _stats(cfg, fidelity: str, n: int = 100) -> tuple[float, float, float]:
    world = World.from_config(cfg)
    sensor = RadarSensor(world, cfg.radar.model_copy(update={"fidelity": fidelity}))
    rng = np.random.default_rng(5)
    hits, errs, counts = [], [], []
    for _ in range(n):
        pose = np.array([*rng.uniform(0.3, 4.7, 2), rng.uniform(-np.pi, np.pi)])
        vel = rng.uniform(0, 2) * np.array([np.cos(pose[2]), np.sin(pose[2])])
        det = sensor.measure(pose, vel, rng)
        counts.append(len(det))
        for true in world.true_distances_m(pose[:2]):
            e = det.range_m - true
            ok = len(det) > 0 and np.min(np.abs(e)) < 0.1
            hits.append(ok)
            if ok:
                errs.append(e[np.argmin(np.abs(e))])
    return float(np.mean(hits)), float(np.std(errs)), float(np.mean(counts))


def test_detections_fidelity_matches_signal_model(paper_cfg):
    rate_s, err_s, n_s = _stats(paper_cfg, "signal")
    rate_f, err_f, n_f = _stats(paper_cfg, "detections")
    assert abs(rate_s - rate_f) < 0.15, (rate_s, rate_f)  # LRP found within 10 cm
    assert 0.5 < err_f / err_s < 2.0, (err_s, err_f)  # range error spread (incl. merging)
    assert 0.65 < n_f / n_s < 1.5, (n_s, n_f)  # detections per frame (merged/missed paths)
