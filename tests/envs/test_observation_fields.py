"""The named fields of the flat observation address what ``observe`` actually put there."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.config import ObservationConfig
from lrp_gym.envs.observations import EstimatedPoseObservation, NavSnapshot
from lrp_gym.envs.task import WaypointPath


@pytest.mark.parametrize("n_waypoints", [1, 3, 5])
def test_fields_cover_the_vector_and_hold_the_snapshot(n_waypoints):
    room = np.array([6.0, 4.0, 3.0])
    obs_type = EstimatedPoseObservation(ObservationConfig(n_waypoints=n_waypoints), room)
    path = WaypointPath.from_points(np.array([[1.0, 1.0], [3.0, 1.0], [3.0, 3.0], [5.0, 3.0]]))
    snap = NavSnapshot(
        est_pose=np.array([1.5, 1.0, 0.0]),
        est_std=np.array([0.1, 0.2, 0.3]),
        converged=True,
        confidence=0.75,
        n_modes=2,
        true_pose=np.array([1.4, 1.1, 0.1]),
        path=path,
        s_est_m=0.5,
        s_true_m=0.4,
        last_action=np.array([0.25, -0.5]),
        room_size_m=room,
    )
    vec = obs_type.observe(snap)
    f = EstimatedPoseObservation.fields(n_waypoints)
    # The slices tile the vector exactly, in order.
    spans = sorted((s.start, s.stop) for s in f.values())
    assert spans[0][0] == 0 and spans[-1][1] == len(vec)
    assert all(a[1] == b[0] for a, b in zip(spans, spans[1:], strict=False))
    assert EstimatedPoseObservation.n_waypoints_of(len(vec)) == n_waypoints
    np.testing.assert_allclose(vec[f["std"]], snap.est_std, rtol=1e-6)
    np.testing.assert_allclose(vec[f["last_action"]], snap.last_action)
    np.testing.assert_allclose(vec[f["position"]], [1.5 / 6.0, 1.0 / 4.0], rtol=1e-6)
    assert vec[f["converged"]][0] == 1.0
    assert vec[f["confidence"]][0] == pytest.approx(0.75)
    assert vec[f["unimodality"]][0] == pytest.approx(0.5)  # two modes
    # The goal (5, 3) seen from (1.5, 1.0) heading 0.
    np.testing.assert_allclose(vec[f["goal"]], [3.5, 2.0], rtol=1e-6)


def test_a_length_that_fits_no_layout_is_refused():
    with pytest.raises(ValueError, match="observation"):
        EstimatedPoseObservation.n_waypoints_of(15)
