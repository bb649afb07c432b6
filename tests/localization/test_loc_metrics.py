import numpy as np
import pytest

from lrp_gym.localization.metrics import (
    STUCK_WRONG_FRAMES,
    frames_to_localised,
    longest_wrong_stretch,
    reliability,
    trust_metrics,
)


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


def test_longest_wrong_stretch_counts_converged_wrong_frames_in_a_row():
    err = np.array([1.0, 1.0, 1.0, 0.1, 1.0, 1.0, 0.5, 0.05])
    conv = np.array([False, True, True, True, True, True, True, True])
    # Frames 1-2 (then right), frames 4-6: the longest run is 3; unconverged frame 0 is not.
    assert longest_wrong_stretch(err, conv) == 3
    assert longest_wrong_stretch(err, np.zeros(8, bool)) == 0
    assert longest_wrong_stretch(np.full(12, 0.31), np.ones(12, bool)) == 12


def test_stuck_wrong_rate_is_per_episode_not_per_step():
    n = STUCK_WRONG_FRAMES
    stuck = (np.full(10 * n, 1.0), np.ones(10 * n, bool))  # one long wrong episode
    brief = (np.tile([1.0, 0.1], 5 * n), np.ones(10 * n, bool))  # wrong every other frame
    clean = (np.full(10 * n, 0.05), np.ones(10 * n, bool))
    m = trust_metrics(*zip(stuck, brief, clean, strict=True))
    assert m["stuck_wrong_rate"] == pytest.approx(1 / 3)
    assert m["confidently_wrong_rate"] == pytest.approx(0.5)


def test_reliability_bins_resolve_the_converged_band_and_count_wrong_steps():
    conf = np.array([0.1, 0.91, 0.93, 0.97, 0.995, 1.0, 1.0])
    errors = np.array([1.0, 0.25, 0.5, 0.05, 0.4, 0.01, 0.02])
    rows = {(r["lo"], r["hi"]): r for r in reliability(conf, errors)}
    assert rows[(0.9, 0.95)]["steps"] == 2
    assert rows[(0.9, 0.95)]["localised_share"] == 0.0  # 0.25 m: not localised, not wrong
    assert rows[(0.9, 0.95)]["wrong_share"] == 0.5  # 0.5 m > 0.3 m
    assert rows[(0.99, 1.0)]["steps"] == 3  # a confidence of 1 falls in the last bin
    assert rows[(0.99, 1.0)]["wrong_share"] == pytest.approx(1 / 3)
    assert rows[(0.2, 0.4)]["steps"] == 0 and rows[(0.2, 0.4)]["wrong_share"] is None
    assert len(reliability(conf, errors, bins=4)) == 4


def test_reliability_rejects_edges_that_do_not_span_0_to_1():
    with pytest.raises(ValueError, match="bins"):
        reliability(np.array([0.5]), np.array([0.1]), bins=[0.0, 0.5, 0.9])
