"""The radar must deliver the LRPs the way the tracker needs them (paper scenario, noise on)."""

from __future__ import annotations

from lrp_gym.radar.delivery_rate import lrp_detection_rate


def test_lrps_detected_with_rcs_in_tracker_window(paper_cfg):
    assert paper_cfg.radar.noise and paper_cfg.radar.cfar.method == "OS"
    res = lrp_detection_rate(paper_cfg, n_poses=300, seed=11)
    # within 10 cm and RCS in [peak - 8 - 6 dB, peak + 8 dB]; measured 0.93-0.95 on 500 poses
    assert res.rate >= 0.90, res
    assert abs(res.median_rcs_error_db) < 2.0, res  # RCS estimate centred on the true RCS
    assert res.range_error_std_m < 0.04, res


def test_detections_fidelity_delivers_like_the_signal_model(paper_cfg):
    sig = lrp_detection_rate(paper_cfg, n_poses=200, seed=12, fidelity="signal")
    fast = lrp_detection_rate(paper_cfg, n_poses=200, seed=12, fidelity="detections")
    assert fast.rate >= 0.90
    assert abs(fast.rate - sig.rate) < 0.06, (sig, fast)
    assert abs(fast.median_rcs_error_db - sig.median_rcs_error_db) < 1.0, (sig, fast)
