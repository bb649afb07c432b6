"""The detections-level model must keep the signal model's statistics (paper scenario)."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.radar import detection_model
from lrp_gym.radar.calibrate import sweep
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
    assert abs(rate_s - rate_f) < 0.06, (rate_s, rate_f)  # LRP found within 10 cm
    assert 0.7 < err_f / err_s < 1.4, (err_s, err_f)  # range error spread (incl. merging)
    assert 0.8 < n_f / n_s < 1.25, (n_s, n_f)  # detections per frame (merged/missed paths)


def test_committed_error_constants_match_a_fresh_fit(paper_cfg):
    res = sweep(paper_cfg, snrs_db=(16.0, 25.0), trials=150, seed=1)
    assert res["RANGE_ERROR_K"] == pytest.approx(detection_model.RANGE_ERROR_K, rel=0.15)
    assert res["DOPPLER_ERROR_K"] == pytest.approx(detection_model.DOPPLER_ERROR_K, rel=0.15)
    # isolated targets: both fidelities detect alike at the edge of detectability
    for row in res["rows"]:
        assert abs(row["pd_signal"] - row["pd_detections"]) < 0.08, row


def test_merge_kernel_numba_and_numpy_agree():
    from lrp_gym.radar._merge import greedy_owner

    rng = np.random.default_rng(4)
    for _ in range(50):
        n = int(rng.integers(1, 60))
        rb = rng.uniform(0, 40, n)
        db = rng.uniform(-16, 16, n)
        a = greedy_owner(rb, db, 2.0, 1.8, 32, use_numba=True)
        b = greedy_owner(rb, db, 2.0, 1.8, 32, use_numba=False)
        np.testing.assert_array_equal(a, b)
        assert np.all(a <= np.arange(n)) and np.all(a[a] == a)  # owners are heads


@pytest.mark.parametrize("fidelity", ["signal", "detections"])
def test_a_turn_on_the_spot_changes_no_detection(paper_cfg, fidelity):
    # The radar sits on the robot's vertical axis with a pattern symmetric about the vertical:
    # the heading moves no path, so a frame after a turn on the spot holds no new evidence
    # (why localization.frame_evidence weighs it 0). A pure rotation gives no radial velocity.
    world = World.from_config(paper_cfg)
    sensor = RadarSensor(world, paper_cfg.radar.model_copy(update={"fidelity": fidelity}))
    at_rest = np.zeros(2)
    for x, y in ((1.0, 1.5), (3.2, 2.4), (2.5, 4.1)):
        frames = [
            sensor.measure(np.array([x, y, theta]), at_rest, np.random.default_rng(11))
            for theta in (0.0, 1.3, -2.7)
        ]
        assert len(frames[0]) > 0
        for other in frames[1:]:
            np.testing.assert_array_equal(other.range_m, frames[0].range_m)
            np.testing.assert_array_equal(other.velocity_mps, frames[0].velocity_mps)
            np.testing.assert_array_equal(other.power_dbm, frames[0].power_dbm)
