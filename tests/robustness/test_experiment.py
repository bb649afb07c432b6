"""The robustness matrix end to end on a tiny grid, and its pieces."""

from __future__ import annotations

import json

import numpy as np
import pytest

from lrp_gym.cli import main
from lrp_gym.experiments.episodes import EpisodeResult
from lrp_gym.experiments.intervals import wilson_interval
from lrp_gym.experiments.robustness import (
    cell_overrides,
    cell_statistics,
    recovery_frames,
    run_matrix,
    suspect_counts,
)


def test_recovery_frames_counts_from_the_kidnap_frame():
    err = np.array([0.1, 0.1, 2.0, 1.5, 0.5, 0.15, 0.1])  # frames 1..7, kidnap at frame 3
    assert recovery_frames(err, 3) == 3  # frame 6 is the first one back under 0.2 m
    assert recovery_frames(err, 1) == 0
    assert recovery_frames(np.array([0.1, 3.0, 3.0]), 2) is None


def _episode(seed, success, errors, converged=None):
    e = np.asarray(errors, float)
    n = len(e)
    return EpisodeResult(
        seed=seed,
        success=success,
        collision=not success,
        steps=n,
        episode_return=0.0,
        path_length_m=0.0,
        time_to_goal_s=None,
        loc_error_m=e,
        converged=np.ones(n, bool) if converged is None else np.asarray(converged, bool),
        cross_track_m=np.zeros(n),
        true_xy=np.zeros((n + 1, 2)),
        est_xy=np.zeros((n + 1, 2)),
        waypoints_m=np.zeros((2, 2)),
    )


def test_a_hidden_reflector_has_its_naming_budget_from_the_frame_it_disappeared():
    from dataclasses import replace

    ep = _episode(0, True, [0.05] * 80)
    # Moved before the episode (after frame 0), named at frame 40: in time; at 41: late.
    moved = replace(ep, perturbed_reflectors=(2,), perturbed_after_frame=(0,))
    assert suspect_counts([replace(moved, suspect_first_frame={2: 40})]) == (1, 1, 0)
    assert suspect_counts([replace(moved, suspect_first_frame={2: 41})]) == (0, 1, 0)
    # Hidden from frame 20 (after frame 19): named at frame 59 is within 40 frames of it.
    hidden = replace(ep, perturbed_reflectors=(1,), perturbed_after_frame=(19,))
    assert suspect_counts([replace(hidden, suspect_first_frame={1: 59})]) == (1, 1, 0)
    assert suspect_counts([replace(hidden, suspect_first_frame={1: 60, 3: 5})]) == (0, 1, 1)
    # Old results without the onsets count from the episode's start.
    legacy = replace(ep, perturbed_reflectors=(1,), suspect_first_frame={1: 41})
    assert suspect_counts([legacy]) == (0, 1, 0)


def test_cell_statistics_intervals_and_trust_metrics():
    # 10 episodes of 20 steps: 7 localised from frame 2 on and successful, 3 never localised
    # (error 1 m, converged: confidently wrong) and failed.
    good = [0.5, 0.5] + [0.05] * 18
    results = [_episode(i, True, good) for i in range(7)]
    results += [_episode(7 + i, False, [1.0] * 20) for i in range(3)]
    recov = [3, 5, None, 20]
    c = cell_statistics("kidnapping", 1.0, results, recov, np.random.default_rng(0))
    ci = c["ci95"]
    assert c["success_rate"] == 0.7 and ci["success_rate"] == list(wilson_interval(7, 10))
    assert ci["collision_rate"] == list(wilson_interval(3, 10))
    assert c["time_localised"] == pytest.approx(7 * 18 / 200)
    # Steps of one episode are not independent: the interval is as wide as 10 episodes allow.
    lo, hi = ci["time_localised"]
    assert lo < c["time_localised"] < hi and hi - lo > 0.3
    # Converged steps off by more than 0.3 m: 3 x 20 bad episodes + 7 x 2 bad first frames.
    assert c["confidently_wrong_rate"] == pytest.approx((60 + 14) / 200)
    assert ci["confidently_wrong_rate"][0] <= c["confidently_wrong_rate"]
    # Never localised counts as the episode's length (20): median of 7 x 2 and 3 x 20.
    assert c["median_frames_to_localised"] == 2.0
    assert ci["median_frames_to_localised"][0] == 2.0
    # Recovery: median over the recovered kidnaps, the budget share over all of them.
    assert c["recovery_frames"] == 5.0 and c["recovered_within_budget"] == 0.5
    assert ci["recovered_within_budget"] == list(wilson_interval(2, 4))
    assert 3.0 <= ci["recovery_frames"][0] <= ci["recovery_frames"][1] <= 20.0
    again = cell_statistics("kidnapping", 1.0, results, recov, np.random.default_rng(0))
    assert again["ci95"] == ci  # the bootstrap is seeded


def test_cell_statistics_without_kidnaps_has_no_recovery_interval():
    c = cell_statistics("none", 0.0, [_episode(0, True, [0.05] * 5)], [], np.random.default_rng(0))
    assert c["ci95"]["recovered_within_budget"] is None and c["ci95"]["recovery_frames"] is None
    assert c["ci95"]["p95_loc_error_m"] == [pytest.approx(0.05)] * 2


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
        lo, hi = c["ci95"]["success_rate"]
        assert lo <= c["success_rate"] <= hi
        assert {"confidently_wrong_rate", "median_frames_to_localised"} <= set(c)
    # Every detection dropped: AMCL never gets a fingerprint, so the uniform prior stays spread.
    assert cells[2]["p95_loc_error_m"] > 1.0 and cells[2]["time_localised"] < 0.05
    kid = cells[1]
    assert kid["kidnapped_episodes"] <= 1 and cells[0]["kidnapped_episodes"] == 0
    assert plot.stat().st_size > 1000
