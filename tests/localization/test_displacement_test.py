"""The parity-space displacement test: position errors project out, a moved reflector adds up."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.localization.displacement_test import DisplacementTest

# Four reflectors at the corners of a 6 x 4 m room (floor plane: the test is geometric).
REFLECTORS = np.array([[0.3, 0.3], [5.7, 0.4], [5.6, 3.7], [0.4, 3.6]])


def _loop(n_frames: int) -> np.ndarray:
    """Robot positions on an ellipse through the room (frames of a patrol)."""
    phi = np.linspace(0.0, 2.0 * np.pi, n_frames, endpoint=False)
    return np.column_stack([3.0 + 1.8 * np.cos(phi), 2.0 + 1.1 * np.sin(phi)])


def _frame(true_xy, est_xy, reflectors_true, rng, noise_m):
    """Residuals (measured from the true pose minus predicted from the estimate) and the
    bearings from the estimate to the mapped reflectors."""
    measured = np.linalg.norm(reflectors_true - true_xy, axis=1)
    measured += rng.normal(0.0, noise_m, len(measured))
    predicted = np.linalg.norm(REFLECTORS - est_xy, axis=1)
    bearing = (REFLECTORS - est_xy) / predicted[:, None]
    return measured - predicted, bearing


def _run(test, moved=None, shift=(0.0, 0.0), pose_error=(0.0, 0.0), noise_m=0.02, n=80, seed=0):
    rng = np.random.default_rng(seed)
    truth = REFLECTORS.copy()
    if moved is not None:
        truth[moved] += shift
    judged = np.ones(len(REFLECTORS), bool)
    for xy in _loop(n):
        residual, bearing = _frame(xy, xy + np.asarray(pose_error), truth, rng, noise_m)
        test.add(judged, residual, bearing)
    return test


def test_a_position_error_alone_projects_out():
    # A 6 cm estimate error shifts every residual by up to 6 cm, always to one side as seen
    # from each reflector: a one-sided bias test would call them all moved.
    t = _run(DisplacementTest(4, 0.02, 0.15, 10_000), pose_error=(0.06, -0.03), noise_m=1e-4)
    assert np.all(t.statistic < 2.0)


def test_statistic_is_chi_square_with_two_degrees_of_freedom_when_nothing_moved():
    stats = np.concatenate(
        [_run(DisplacementTest(4, 0.02, 0.15, 10_000), seed=s).statistic for s in range(60)]
    )
    assert stats.mean() == pytest.approx(2.0, abs=0.35)  # E[chi2_2] = 2
    assert np.mean(stats > 20.0) < 0.01  # P(chi2_2 > 20) = 4.5e-5


@pytest.mark.parametrize("moved", [0, 1, 2, 3])
def test_a_quarter_metre_move_is_named_despite_a_pose_error(moved):
    # The move is perpendicular to the line from the room's centre: small in any one frame
    # (under the 0.1 m gate) from most of the loop.
    c = REFLECTORS[moved] - np.array([3.0, 2.0])
    shift = 0.25 * np.array([-c[1], c[0]]) / np.linalg.norm(c)
    t = _run(DisplacementTest(4, 0.02, 0.3, 10_000), moved, shift, pose_error=(0.03, 0.02))
    assert t.leader(20.0, 10.0) == moved
    assert t.displacement_m[moved] == pytest.approx(shift, abs=0.05)


def test_returns_beyond_the_gate_and_frames_with_two_reflectors_are_left_out():
    t = DisplacementTest(4, 0.02, 0.15, 100)
    bearing = (REFLECTORS - [3.0, 2.0]) / np.linalg.norm(REFLECTORS - [3.0, 2.0], axis=1)[:, None]
    t.add(np.array([True, True, False, False]), np.full(4, 0.05), bearing)  # two judged
    t.add(np.ones(4, bool), np.array([0.0, 0.0, 0.0, 0.5]), bearing)  # the 0.5 m is out
    assert np.all(t.normal_m2[:2] != 0.0) and np.all(t.normal_m2[3] == 0.0)
    assert np.all(t.statistic < 1e-9)  # three residuals of 0: nothing seen
    assert t.leader(20.0, 10.0) is None
