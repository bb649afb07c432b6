"""The robustness table reads at 80 columns: every perturbation name on one line, intervals
whole even at their widest."""

from __future__ import annotations

from lrp_gym.commands import robustness
from lrp_gym.experiments import robustness as rb
from lrp_gym.experiments.robustness import PERTURBATION_NAMES


def test_table_fits_80_columns_unfolded(capsys, monkeypatch):
    monkeypatch.setattr(robustness.console, "width", 80)
    # The widest values each column can show: 3-digit intervals, metres of error, long recoveries.
    cell = {
        "severity": 0.25,
        "success_rate": 0.5,
        "collision_rate": 0.5,
        "p50_loc_error_m": 0.04,
        "p95_loc_error_m": 3.912,
        "time_localised": 0.96,
        "confidently_wrong_rate": 0.333,
        "median_frames_to_localised": 124.5,
        "recovery_frames": 112.5,
        "recovered_within_budget": 0.9,
        "ci95": {
            "success_rate": [0.237, 1.0],
            "collision_rate": [0.237, 1.0],
            "p95_loc_error_m": [1.234, 4.567],
            "time_localised": [0.123, 1.0],
            "confidently_wrong_rate": [0.123, 1.0],
            "median_frames_to_localised": [100.5, 299.5],
            "recovery_frames": [100.5, 299.5],
            "recovered_within_budget": [0.237, 1.0],
        },
    }
    result = {
        "agent": "pure-pursuit",
        "env_id": "LRPRadarNav-v0",
        "scenario": "ipin2023-2types-patrol",
        "task": None,
        "episodes": 50,
        "seed": 0,
        "cells": [cell | {"perturbation": name} for name in PERTURBATION_NAMES],
    }
    robustness._print(result, 15)
    out = capsys.readouterr().out
    assert max(len(line) for line in out.splitlines()) <= 80, out
    rows = [line.split() for line in out.splitlines()]
    assert all(any(name in r for r in rows) for name in PERTURBATION_NAMES), out
    # Intervals are printed whole (no ellipsis, no folding into a third line).
    assert any("100-300" in r for r in rows) and any("123-457" in r for r in rows), out
    assert "…" not in out


def test_cli_default_episodes_is_the_experiments():
    assert robustness.DEFAULT_EPISODES == rb.DEFAULT_EPISODES >= 50
    assert robustness.BASELINE == rb.BASELINE
