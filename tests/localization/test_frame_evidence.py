"""A frame at the same spot repeats the last one's evidence: it must not sharpen the cloud."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lrp_gym.config import load_scenario
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.frame_evidence import FrameEvidence, independence_weight
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world import World


def test_the_weight_is_the_effective_share_of_an_ar1_process():
    assert independence_weight(0.0, 0.03) == 0.0  # the same spot: nothing new
    assert independence_weight(math.inf, 0.03) == 1.0  # the first frame
    assert independence_weight(0.0, None) == 1.0  # the model off
    # rho = 1/3 at d = L ln 3: (1 - 1/3) / (1 + 1/3) = 1/2
    assert independence_weight(0.03 * math.log(3.0), 0.03) == pytest.approx(0.5)
    d = np.linspace(0.0, 0.3, 31)
    w = [independence_weight(x, 0.03) for x in d]
    assert np.all(np.diff(w) > 0.0) and w[-1] > 0.999


def test_the_distance_counts_from_the_last_weighed_frame():
    ev = FrameEvidence(0.5, 0.03)
    assert ev.take() == 0.5  # after construction: an independent frame
    ev.move(-0.02)  # reversing counts as motion too
    ev.move(0.01)
    assert ev.take() == pytest.approx(0.5 * independence_weight(0.03, 0.03))
    assert ev.take() == 0.0  # no motion since
    assert ev.restart() == 0.5


@pytest.mark.parametrize("correlation_m", [0.03, None])
def test_standing_frames_leave_the_weights_as_the_first_left_them(correlation_m):
    cfg = load_scenario("ipin2023")
    loc = cfg.localization.model_copy(
        update={"likelihood_correlation_m": correlation_m, "global_proposal": False}
    )
    world = World.from_config(cfg)
    pose = np.array([2.0, 3.0, 0.3])
    fp = Fingerprint.from_true(world.layout, world.radar_position(pose[:2]))
    amcl = Amcl(world, loc)
    amcl.reset(np.random.default_rng(0), pose=pose)
    amcl.update(np.zeros(3), fp, np.random.default_rng(1))
    first = amcl.estimate()
    spread = []
    for k in range(5):  # standing: zero odometry, the same frame again
        amcl.update(np.zeros(3), fp, np.random.default_rng(2 + k))
        spread.append(
            float(
                np.sqrt(
                    np.average(
                        np.sum((amcl.particles[:, :2] - pose[:2]) ** 2, 1), weights=amcl.weights
                    )
                )
            )
        )
    # motion noise is zero at zero odometry, so only the weights can sharpen the cloud
    if correlation_m is None:
        assert spread[-1] < 0.8 * spread[0], spread  # five copies counted as evidence
    else:
        assert spread[-1] > 0.9 * spread[0], spread  # no sharper than after the first
    assert np.hypot(*(first.pose[:2] - pose[:2])) < 0.2


@pytest.mark.parametrize("correlation_m", [0.03, None])
def test_standing_frames_do_not_make_a_wrong_cloud_look_found(correlation_m):
    # A cloud 1.5 m from where the frames are taken. The robot then turns on the spot: the
    # same frame again. It may still raise the lost test's statistics (a kidnap at standstill
    # looks like standing to the odometry) but never lower them: repeated, a wrong cloud's
    # fit a little better than the drift used to decay p_lost, and a robot turning on the
    # spot under clutter read a wrong cloud as found (docs/trust.md, session 19).
    cfg = load_scenario("ipin2023")
    loc = cfg.localization.model_copy(update={"likelihood_correlation_m": correlation_m})
    world = World.from_config(cfg)
    pose = np.array([2.0, 3.0, 0.3])
    fp = Fingerprint.from_true(world.layout, world.radar_position(pose[:2] + [1.5, 0.0]))
    amcl = Amcl(world, loc)
    amcl.reset(np.random.default_rng(0), pose=pose)
    amcl.update(np.zeros(3), fp, np.random.default_rng(1))
    amcl.update(np.zeros(3), fp, np.random.default_rng(2))
    amcl.update(np.zeros(3), fp, np.random.default_rng(3))  # the statistics have risen
    peak = amcl.lost.evidence_nats
    assert peak > 1.0
    # the same frame after the cloud has moved onto the truth: the deficit is now negative
    amcl.particles[:, :2] += [1.5, 0.0]
    trace = []
    for k in range(4):
        amcl.update(np.zeros(3), fp, np.random.default_rng(4 + k))
        trace.append(amcl.lost.evidence_nats)
    if correlation_m is None:  # every frame counted anew: found by repetition
        assert trace[-1] < peak - 1.0, (peak, trace)
    else:
        assert trace == [peak] * 4, (peak, trace)


def test_a_frame_that_repeats_the_last_counts_only_against_the_cloud():
    from lrp_gym.localization.proposal import LostTest

    test = LostTest(drift_nats=4.0, threshold_nats=8.0)
    test.update_marginal(20.0, 10.0, 5)  # deficit 10, drift 4
    assert test.statistic_nats == 6.0
    test.update_marginal(11.0, 10.0, 5, frame_weight=0.0)  # 1 - 4 < 0: repeated, ignored
    assert test.statistic_nats == 6.0
    test.update_marginal(11.0, 10.0, 5, frame_weight=0.5)
    assert test.statistic_nats == 4.5
    test.update_marginal(16.0, 10.0, 5, frame_weight=0.0)  # against the cloud: in full
    assert test.statistic_nats == 6.5
