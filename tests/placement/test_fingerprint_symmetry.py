"""Fingerprints, symmetry images and the layout constraint: analytic truths."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.placement import (
    check_constraint,
    constraint_margins,
    fingerprints,
    pair_images,
    unique_fingerprints,
)
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world import World

H = 0.3  # radar mount height


def test_fingerprints_match_the_tracking_contract(paper_cfg):
    world = World.from_config(paper_cfg)
    xy = np.random.default_rng(1).uniform(0, 5, size=(20, 2))
    fp = fingerprints(xy, world.layout.positions_m, world.layout.type_index, world.mount_height_m)
    for row, p in zip(fp, xy, strict=True):
        ref = Fingerprint.from_true(world.layout, world.radar_position(p))
        np.testing.assert_allclose(row, np.concatenate(ref.distances_m))


def test_fingerprints_group_by_type_and_sort_within():
    refl = np.array([[1, 1, 3], [4, 1, 3], [4, 4, 3], [1, 4, 3.0]])
    types = np.array([1, 0, 1, 0])
    xy = np.random.default_rng(2).uniform(0, 5, size=(50, 2))
    fp = fingerprints(xy, refl, types, H)
    d = np.linalg.norm(np.c_[xy, np.full(len(xy), H)][:, None] - refl, axis=-1)
    np.testing.assert_allclose(fp[:, :2], np.sort(d[:, [1, 3]], axis=1))
    np.testing.assert_allclose(fp[:, 2:], np.sort(d[:, [0, 2]], axis=1))
    # Relabelling reflectors of one type does not change the fingerprint.
    np.testing.assert_allclose(fingerprints(xy, refl[[2, 3, 0, 1]], types[[2, 3, 0, 1]], H), fp)


def test_every_pair_image_has_the_same_fingerprint():
    rng = np.random.default_rng(3)
    refl = np.c_[rng.uniform(0, 5, size=(2, 2)), [3.0, 3.0]]
    mats, offs = pair_images(refl[:, :2], np.zeros(2, dtype=int))
    assert mats.shape == (3, 2, 2)
    p = rng.uniform(0, 5, size=(100, 2))
    fp = fingerprints(p, refl, [0, 0], H)
    for a, b in zip(mats, offs, strict=True):
        img = p @ a.T + b
        np.testing.assert_allclose(fingerprints(img, refl, [0, 0], H), fp, atol=1e-12)
        # Isometric involutions: applying twice is the identity.
        np.testing.assert_allclose(img @ a.T + b, p, atol=1e-12)


def test_unique_fingerprints_of_one_reflector_count_radial_bins():
    # One reflector overhead at the centre: the fingerprint is the slant distance only, so the
    # count is the number of distinct distance bins over the positions.
    xy = np.random.default_rng(4).uniform(0, 5, size=(5000, 2))
    refl = np.array([[2.5, 2.5, 3.0]])
    d = np.linalg.norm(np.c_[xy - 2.5, np.full(len(xy), 3.0 - H)], axis=1)
    expected = len(np.unique(np.floor(d / 0.075)))
    assert unique_fingerprints(fingerprints(xy, refl, [0], H), 0.075) == expected


def test_constraint_inherent_structures_for_two_and_three_reflectors():
    two = check_constraint(np.array([[1, 1], [4, 2.0]]), [0, 0], 0.1)
    assert not two.ok and "3 mirror images" in two.structures[0]
    three = check_constraint(np.array([[1, 1], [4, 2.0], [2, 4]]), [0, 0, 0], 0.1)
    assert not three.ok and len(three.structures) == 3
    assert all("ambiguity line" in s for s in three.structures)
    # Three reflectors of three types: trilateration, nothing systematic.
    assert check_constraint(np.array([[1, 1], [4, 2.0], [2, 4]]), [0, 1, 2], 0.1).ok


def test_constraint_four_reflectors():
    # A square: the diagonals' midpoints coincide, so every axis passes through them.
    square = np.array([[1, 1], [4, 1], [4, 4], [1, 4.0]])
    assert not check_constraint(square, [0, 0, 0, 0], 0.1).ok
    # Midpoint of (0, 1) = (2, 2) lies on the line through reflectors 2 and 3 (y = 2).
    on_line = np.array([[1, 1], [3, 3], [0.5, 2], [4.5, 2.0]])
    rep = check_constraint(on_line, [0, 0, 0, 0], 0.1)
    assert not rep.ok and rep.margin_m == pytest.approx(0.0, abs=1e-12)
    assert any("pair (0,1)" in s and "line of pair (2,3)" in s for s in rep.structures)
    good = np.array([[4.588, 4.648], [0.583, 2.928], [0.351, 0.712], [0.958, 4.621]])
    rep = check_constraint(good, [0, 0, 0, 0], 0.1)
    assert rep.ok and rep.margin_m > 0.1


def test_two_types_check_only_same_type_pairs():
    # The square is bad for one type, but as 2 + 2 with each type on a side, the same-type pairs'
    # axes (the side and its bisector) miss the other side's midpoint.
    square = np.array([[1, 1], [4, 1], [4, 4], [1, 4.0]])
    rep = check_constraint(square, [0, 0, 1, 1], 0.1)
    assert not rep.ok  # the bisector x = 2.5 of each side passes the other side's midpoint
    shifted = np.array([[1, 1], [4, 1], [3.5, 4], [0.5, 3.0]])
    assert check_constraint(shifted, [0, 0, 1, 1], 0.1).ok


def test_constraint_margins_vectorised_match_single():
    rng = np.random.default_rng(5)
    batch = rng.uniform(0, 5, size=(30, 4, 2))
    types = np.array([0, 0, 0, 0])
    margins = constraint_margins(batch, types)
    for lay, m in zip(batch, margins, strict=True):
        assert check_constraint(lay, types, 0.0).margin_m == pytest.approx(m)


def test_constraint_margins_equal_the_check_by_check_minimum():
    # The margins are computed for all checks at once; each check alone, as before, gives the
    # same minimum to the last bit (the layout search's sampling depends on it).
    from lrp_gym.placement.symmetry import _line_distance, constraint_checks

    rng = np.random.default_rng(9)
    for types in ([0, 0, 0, 0], [0, 0, 1, 1], [0, 1, 0, 1, 2, 2, 0], [0, 0, 0, 0, 0, 0, 0, 0]):
        xy = rng.uniform(0, 5, size=(40, len(types), 2))
        want = np.full(40, np.inf)
        for (i, j), (k, n), bisector in constraint_checks(types):
            mid, q_mid = (xy[:, i] + xy[:, j]) / 2.0, (xy[:, k] + xy[:, n]) / 2.0
            q_dir = xy[:, n] - xy[:, k]
            want = np.minimum(want, _line_distance(mid, q_mid, q_dir))
            if bisector:
                normal = np.stack([-q_dir[:, 1], q_dir[:, 0]], axis=-1)
                want = np.minimum(want, _line_distance(mid, q_mid, normal))
        np.testing.assert_array_equal(constraint_margins(xy, np.array(types)), want)
        np.testing.assert_array_equal(constraint_margins(xy[0], np.array(types)), want[0])
    assert np.isinf(constraint_margins(rng.uniform(0, 5, (3, 3, 2)), np.array([0, 1, 2]))).all()
