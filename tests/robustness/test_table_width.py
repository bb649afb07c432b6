"""The robustness table reads at 80 columns: every perturbation name on one line."""

from __future__ import annotations

from lrp_gym.commands import robustness
from lrp_gym.experiments.robustness import PERTURBATION_NAMES


def test_table_fits_80_columns_unfolded(capsys, monkeypatch):
    monkeypatch.setattr(robustness.console, "width", 80)
    cell = {
        "severity": 0.25,
        "success_rate": 1.0,
        "collision_rate": 0.0,
        "p50_loc_error_m": 0.04,
        "p95_loc_error_m": 0.081,
        "time_localised": 0.96,
        "recovery_frames": 12.5,
        "recovered_within_budget": 0.9,
    }
    result = {
        "agent": "pure-pursuit",
        "env_id": "LRPRadarNav-v0",
        "scenario": "ipin2023",
        "task": None,
        "episodes": 20,
        "seed": 0,
        "cells": [cell | {"perturbation": name} for name in PERTURBATION_NAMES],
    }
    robustness._print(result, 15)
    out = capsys.readouterr().out
    assert max(len(line) for line in out.splitlines()) <= 80
    rows = [line.split() for line in out.splitlines()]
    assert all(any(name in r for r in rows) for name in PERTURBATION_NAMES), out
