"""The robustness matrix end to end on a tiny grid, and its pieces."""

from __future__ import annotations

import json

import numpy as np
import pytest

from lrp_gym.cli import main
from lrp_gym.experiments.robustness import cell_overrides, recovery_frames, run_matrix


def test_recovery_frames_counts_from_the_kidnap_frame():
    err = np.array([0.1, 0.1, 2.0, 1.5, 0.5, 0.15, 0.1])  # frames 1..7, kidnap at frame 3
    assert recovery_frames(err, 3) == 3  # frame 6 is the first one back under 0.2 m
    assert recovery_frames(err, 1) == 0
    assert recovery_frames(np.array([0.1, 3.0, 3.0]), 2) is None


def test_cell_overrides():
    assert cell_overrides("none", 0.0) == {}
    assert cell_overrides("clutter", 0.5) == {"perturbations": {"clutter": {"severity": 0.5}}}


def _no_policy(env):
    raise AssertionError("the arguments are checked before any env or policy is built")


def test_bad_matrix_arguments_are_value_errors_naming_the_argument():
    with pytest.raises(ValueError, match="^perturbations: "):
        run_matrix(_no_policy, perturbations=["quake"], episodes=1)
    with pytest.raises(ValueError, match="^severities: "):
        run_matrix(_no_policy, perturbations=["clutter"], severities=[1.5], episodes=1)


def test_cli_names_the_flag_of_a_bad_matrix_argument(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["robustness", "--severities", "2", "--episodes", "1"])
    assert exc.value.code == 2
    assert "error: --severities:" in capsys.readouterr().err


def test_tiny_matrix_end_to_end_via_cli(capsys, tmp_path):
    plot = tmp_path / "m.png"
    with pytest.raises(SystemExit) as exc:
        main(
            [
                "robustness",
                "--fidelity",
                "detections",
                "--episodes",
                "1",
                "--severities",
                "1",
                "--agent",
                "oracle",
                "--perturbations",
                "kidnapping,missed_detections",
                "--json",
                "--plot",
                str(plot),
            ]
        )
    assert exc.value.code in (0, None)
    doc = json.loads(capsys.readouterr().out)
    cells = doc["cells"]
    assert [(c["perturbation"], c["severity"]) for c in cells] == [
        ("none", 0.0),
        ("kidnapping", 1.0),
        ("missed_detections", 1.0),
    ]
    for c in cells:
        assert {
            "perturbation",
            "severity",
            "success_rate",
            "p95_loc_error_m",
            "recovery_frames",
        } <= set(c)
        assert 0.0 <= c["success_rate"] <= 1.0
    # Every detection dropped: AMCL never gets a fingerprint, so the uniform prior stays spread.
    assert cells[2]["p95_loc_error_m"] > 1.0 and cells[2]["time_localised"] < 0.05
    kid = cells[1]
    assert kid["kidnapped_episodes"] <= 1 and cells[0]["kidnapped_episodes"] == 0
    assert plot.stat().st_size > 1000
