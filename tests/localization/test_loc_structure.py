"""The room-structure term of the likelihood: predictable room returns become evidence."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.structure import structure_ranges_m


def test_structure_ranges_follow_the_room(paper_world):
    room, h = paper_world.room, paper_world.mount_height_m
    g = structure_ranges_m(room, h, np.array([[1.0, 2.0]]))[:, 0]
    up = room.size_m[2] - h
    assert g[0] == pytest.approx(up)  # ceiling: same everywhere
    assert g[1] == pytest.approx(np.hypot(1.0, up))  # edge of the wall x = 0
    assert g[2] == pytest.approx(np.hypot(room.size_m[0] - 1.0, up))
    assert np.allclose(g[5:], [1.0, room.size_m[0] - 1.0, 2.0, room.size_m[1] - 2.0])


def _model(world, s):
    return FingerprintModel(
        world.layout,
        world.mount_height_m,
        0.075,
        0.2,
        20.0,
        room=world.room,
        structure_probability=s,
    )


def test_structure_return_is_evidence_for_the_pose_that_predicts_it(paper_world):
    true_xy = np.array([1.5, 2.5])
    other_xy = np.array([3.2, 1.1])
    fp_true = Fingerprint.from_true(paper_world.layout, paper_world.radar_position(true_xy), 0.02)
    # Add the true pose's wall-ceiling edge return as an extra (reflector-like) distance.
    edge = structure_ranges_m(paper_world.room, paper_world.mount_height_m, true_xy[None])[1, 0]
    fp = Fingerprint.from_distances(
        fp_true.type_names, [np.append(fp_true.distances_m[0], edge)], 0.02
    )
    xy = np.stack([true_xy, other_xy])
    with_s = _model(paper_world, 0.4).log_likelihood(xy, fp)
    without = _model(paper_world, 0.0).log_likelihood(xy, fp)
    # The extra distance is explained at the true pose only when the model knows the room.
    gain_true = with_s[0] - without[0]
    gain_other = with_s[1] - without[1]
    assert gain_true > gain_other + 1.0
    assert with_s[0] > with_s[1]


def test_zero_structure_probability_is_the_plain_model(paper_world):
    rng = np.random.default_rng(0)
    xy = rng.uniform(0.5, 4.5, (200, 2))
    fp = Fingerprint.from_distances(("A",), [np.array([2.9, 3.4, 4.4, 5.0, 3.7])], 0.02)
    a = _model(paper_world, 0.0).log_likelihood(xy, fp)
    b = FingerprintModel(
        paper_world.layout, paper_world.mount_height_m, 0.075, 0.2, 20.0
    ).log_likelihood(xy, fp)
    assert np.allclose(a, b)
