"""The reported ``converged`` flag and the localiser's own ``settled`` flag."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import lrp_gym  # noqa: F401  (registers the ids)
from lrp_gym.config import LocalizationConfig
from lrp_gym.localization.pose_estimate import cloud_estimate, convergence_flags


def test_flags_follow_their_own_mass_and_share_the_spread_test():
    cfg = LocalizationConfig(converged_mass=0.99, settled_mass=0.9)
    tight, loose = 0.05**2, 0.3**2  # converged_std_m is 0.25 m
    assert convergence_flags(0.95, tight, cfg) == (False, True)
    assert convergence_flags(0.995, tight, cfg) == (True, True)
    assert convergence_flags(0.85, tight, cfg) == (False, False)
    assert convergence_flags(0.995, loose, cfg) == (False, False)


def test_a_cloud_with_a_twentieth_elsewhere_is_settled_not_converged():
    rng = np.random.default_rng(0)
    cfg = LocalizationConfig(converged_mass=0.99, settled_mass=0.9)
    main = np.column_stack([rng.normal([1.0, 1.0], 0.03, (950, 2)), rng.normal(0.2, 0.05, 950)])
    far = np.column_stack([rng.normal([3.5, 3.0], 0.03, (50, 2)), rng.normal(0.2, 0.05, 50)])
    size = np.array([5.0, 5.0])
    w = np.full(1000, 1e-3)
    est = cloud_estimate(np.vstack([main, far]), w, cfg, size, 1000.0, 0.0)
    assert est.confidence == pytest.approx(0.95, abs=0.005)
    assert est.settled and not est.converged
    whole = cloud_estimate(main, np.full(950, 1.0 / 950), cfg, size, 950.0, 0.0)
    assert whole.settled and whole.converged
    # The lost test's doubt counts in both: p_lost 0.2 leaves 0.8 of the mode.
    doubted = cloud_estimate(main, np.full(950, 1.0 / 950), cfg, size, 950.0, 0.2)
    assert not doubted.settled and not doubted.converged


def _rollout(converged_mass: float) -> tuple[np.ndarray, list[bool], np.ndarray]:
    loc = {"converged_mass": converged_mass, "clutter_map": {"enabled": True}}
    over = {"localization": loc, "perturbations": {"clutter": {"severity": 0.5}}}
    env = gym.make("LRPRadarNavFast-v0", overrides=over)
    env.reset(seed=3)
    actions = np.random.default_rng(1).uniform([0.0, -0.4], [0.6, 0.4], (40, 2))
    poses, flags = [], []
    for a in actions:
        _, _, term, trunc, info = env.step(a.astype(np.float32))
        poses.append(info["est_pose"])
        flags.append(bool(info["converged"]))
        if term or trunc:
            break
    points = env.unwrapped.stack.clutter_map.points.copy()
    env.close()
    return np.array(poses), flags, points


def test_the_reported_threshold_does_not_feed_back_into_the_localiser():
    """The clutter map, reflector monitor, tracker prior and lost test act on ``settled``:
    moving ``converged_mass`` changes what is reported, not a single estimate (under clutter,
    with the clutter map on, so that what it learns would show)."""
    strict, strict_flags, strict_points = _rollout(0.999)
    lax, lax_flags, lax_points = _rollout(0.5)
    np.testing.assert_array_equal(strict, lax)
    np.testing.assert_array_equal(strict_points, lax_points)
    assert sum(lax_flags) > sum(strict_flags)  # the claim is what moved
