"""The default observation carries the localiser's confidence and mode count of the same step."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.envs.nav_env import LRPRadarNavEnv
from lrp_gym.envs.observations import EstimatedPoseObservation, unimodality

FAST = {"radar_fidelity": "detections"}


def _steps(env, seed, n=12):
    """(observation, info) at reset and after each of ``n`` steps of a fixed gentle action."""
    obs, info = env.reset(seed=seed)
    out = [(obs, info)]
    for _ in range(n):
        obs, _, term, trunc, info = env.step(np.array([0.3, 0.1], np.float32))
        out.append((obs, info))
        if term or trunc:
            break
    return out


def test_unimodality_is_bounded_and_falls_with_the_mode_count():
    assert unimodality(1) == 1.0 and unimodality(2) == 0.5 and unimodality(4) == 0.25
    assert unimodality(0) == 0.0  # no mode holds 5 %: the diffuse (lost) end
    values = [unimodality(n) for n in range(0, 30)]
    assert all(0.0 <= v <= 1.0 for v in values)
    assert all(a > b for a, b in zip(values[1:], values[2:], strict=False))


def test_estimated_observation_holds_info_confidence_and_modes():
    env = LRPRadarNavEnv(**FAST)
    f = EstimatedPoseObservation.fields(env.cfg.env.observation.n_waypoints)
    confidences, modes = [], []
    for seed in (0, 1, 2):
        for obs, info in _steps(env, seed):
            assert env.observation_space.contains(obs)
            conf, uni = obs[f["confidence"]][0], obs[f["unimodality"]][0]
            assert 0.0 <= conf <= 1.0 and 0.0 <= uni <= 1.0
            assert conf == pytest.approx(info["localization_confidence"], abs=1e-6)
            assert uni == pytest.approx(unimodality(info["n_modes"]), abs=1e-6)
            assert obs[f["converged"]][0] == float(info["converged"])
            confidences.append(conf)
            modes.append(info["n_modes"])
    # The features move with the localiser (a global start is unsure, then it converges).
    assert min(confidences) < 0.5 < max(confidences)
    assert len(set(modes)) > 1


def test_oracle_reports_certainty_and_dict_matches_estimated():
    oracle = LRPRadarNavEnv(observation="oracle", **FAST)
    f = EstimatedPoseObservation.fields(oracle.cfg.env.observation.n_waypoints)
    steps = _steps(oracle, 0, n=4)
    for obs, _ in steps:
        assert obs[f["confidence"]][0] == 1.0 and obs[f["unimodality"]][0] == 1.0
    # ... while the filter itself is still unsure at some step.
    assert min(info["localization_confidence"] for _, info in steps) < 1.0

    as_dict = LRPRadarNavEnv(observation="dict", **FAST)
    flat = LRPRadarNavEnv(**FAST)
    for (d, _), (v, _) in zip(_steps(as_dict, 3, n=5), _steps(flat, 3, n=5), strict=True):
        assert as_dict.observation_space.contains(d)
        assert d["confidence"][0] == v[f["confidence"]][0]
        assert d["unimodality"][0] == v[f["unimodality"]][0]
