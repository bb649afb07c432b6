import numpy as np
import pytest

from lrp_gym.localization.metrics import frames_to_localised, reliability, trust_metrics


def test_frames_to_localised_and_never():
    assert frames_to_localised(np.array([1.0, 0.5, 0.1, 0.05])) == 2
    assert frames_to_localised(np.array([1.0, 0.5])) is None


def test_trust_metrics_counts_confidently_wrong_steps_among_converged_ones():
    errors = [np.array([2.0, 1.0, 0.1, 0.1]), np.array([0.5, 0.5, 0.5])]
    conv = [np.array([False, True, True, True]), np.array([False, True, True])]
    m = trust_metrics(errors, conv)
    assert m["time_localised"] == pytest.approx(2 / 7)
    assert m["mean_episode_time_localised"] == pytest.approx((0.5 + 0.0) / 2)
    assert m["median_frames_to_localised"] == pytest.approx((2 + 3) / 2)  # never: its length
    assert m["never_localised_rate"] == 0.5
    assert m["confidently_wrong_rate"] == pytest.approx(3 / 5)  # 1.0, 0.5, 0.5 of 5 converged


def test_reliability_of_a_calibrated_confidence():
    rng = np.random.default_rng(0)
    conf = rng.random(20000)
    errors = np.where(rng.random(20000) < conf, 0.05, 1.0)  # right with probability conf
    for row in reliability(conf, errors, bins=5):
        assert row["localised_share"] == pytest.approx(row["mean_confidence"], abs=0.03)
