"""Ambiguity analysis: symmetry structures of 2, 3 and 4 reflectors, and the KD-tree finder."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.placement import (
    PositionGrid,
    ambiguous_pairs,
    ambiguous_pairs_bruteforce,
    analyse_layout,
    fingerprints,
)
from lrp_gym.world import Room

H = 0.3
ROOM = Room(size_m=np.array([5.0, 5.0, 4.0]))
SEP = 0.3


def z3(xy) -> np.ndarray:
    xy = np.asarray(xy, dtype=float)
    return np.c_[xy, np.full(len(xy), 3.0)]


@pytest.mark.parametrize("types", [[0, 0, 0, 0], [0, 0, 1, 1]])
def test_kdtree_finder_agrees_with_brute_force(types):
    grid = PositionGrid.from_room(ROOM, 0.2)
    rng = np.random.default_rng(7)
    for _ in range(3):
        refl = z3(rng.uniform(0.3, 4.7, size=(4, 2)))
        fp = fingerprints(grid.xy_m, refl, types, H)
        fast = ambiguous_pairs(fp, grid.xy_m, 0.075, SEP)
        slow = ambiguous_pairs_bruteforce(fp, grid.xy_m, 0.075, SEP)
        assert len(slow) > 0
        assert set(map(tuple, fast.tolist())) == set(map(tuple, slow.tolist()))


def _pair_set(grid, refl, types, tol):
    fp = fingerprints(grid.xy_m, refl, types, H)
    return {tuple(p) for p in ambiguous_pairs(fp, grid.xy_m, tol, SEP).tolist()}


def test_two_reflectors_every_mirror_image_is_an_ambiguous_partner():
    # Reflectors symmetric to the grid, so every cell's images are cell centres.
    grid = PositionGrid.from_room(ROOM, 0.1)
    refl = z3([[1.5, 2.5], [3.5, 2.5]])
    res = analyse_layout(refl, [0, 0], grid, H, 0.01, SEP)
    pairs = _pair_set(grid, refl, [0, 0], 0.01)
    lookup = {tuple(np.round(p, 6)): k for k, p in enumerate(grid.xy_m)}
    xy = grid.xy_m
    images = [np.c_[xy[:, 0], 5 - xy[:, 1]], np.c_[5 - xy[:, 0], xy[:, 1]], 5 - xy]
    checked = 0
    for k, p in enumerate(xy):
        for img in images:
            if np.linalg.norm(img[k] - p) > SEP:
                j = lookup[tuple(np.round(img[k], 6))]
                assert (min(k, j), max(k, j)) in pairs
                checked += 1
    assert checked > 2 * len(xy)
    assert res.random_fraction == 0.0
    assert res.systematic_fraction == res.ambiguous_fraction > 0.95
    assert not res.constraint.ok


def test_three_reflectors_ambiguity_lines_have_partners():
    a, b, c = np.array([1.0, 1.0]), np.array([4.0, 1.5]), np.array([2.0, 4.2])
    refl = z3([a, b, c])
    grid = PositionGrid.from_room(ROOM, 0.05)
    res = analyse_layout(refl, [0, 0, 0], grid, H, 0.02, SEP)
    assert res.systematic_fraction > 0.01
    fp = fingerprints(grid.xy_m, refl, [0, 0, 0], H)
    m = (a + b) / 2
    n = np.array([-(m - c)[1], (m - c)[0]]) / np.linalg.norm(m - c)  # along the line
    hits = 0
    for s in np.linspace(-3, 3, 61):
        p = m + s * n
        q = 2 * m - p  # point mirror: swaps d_a, d_b and keeps d_c on this line
        if (
            not (ROOM.free(p[None])[0] and ROOM.free(q[None])[0])
            or np.linalg.norm(p - q) < SEP + 0.15
        ):
            continue
        f_p, f_q = fingerprints(np.array([p, q]), refl, [0, 0, 0], H)
        np.testing.assert_allclose(f_p, f_q, atol=1e-12)  # exact ambiguity
        k = int(np.argmin(np.linalg.norm(grid.xy_m - p, axis=1)))
        assert res.ambiguous[k] and res.systematic[k]
        hits += 1
    assert hits >= 10
    assert fp.shape == (len(grid), 3)


def _line_layouts():
    # Violating: the midpoint (2.025, 2) of reflectors 0, 1 lies on the line y = 2 of 2, 3
    # (x = 2.025 is a column of cell centres of the 0.05 m grid).
    bad = z3([[1.025, 1.0], [3.025, 3.0], [0.5, 2.0], [4.5, 2.0]])
    good = z3([[4.588, 4.648], [0.583, 2.928], [0.351, 0.712], [0.958, 4.621]])
    return bad, good


def test_four_reflectors_violating_the_constraint_show_a_line():
    bad, good = _line_layouts()
    grid = PositionGrid.from_room(ROOM, 0.05)
    res_bad = analyse_layout(bad, [0] * 4, grid, H, 0.01, SEP)
    res_good = analyse_layout(good, [0] * 4, grid, H, 0.01, SEP)
    assert not res_bad.constraint.ok and res_good.constraint.ok
    # The predicted line: through the midpoint, orthogonal to y = 2, i.e. x = 2.025.
    # Partners (4.05 - x, 4 - y) inside the room need y < 4.
    x, y = grid.xy_m.T
    on_line = (np.abs(x - 2.025) < 1e-6) & (np.abs(y - 2.0) > 0.2) & (y < 3.97)
    assert on_line.sum() > 60
    assert res_bad.systematic[on_line].all()
    assert res_bad.systematic_fraction > 0.005
    assert res_good.systematic_fraction < 0.002


def test_valid_two_plus_two_layout_has_no_random_ambiguities():
    _, good = _line_layouts()
    grid = PositionGrid.from_room(ROOM, 0.05)
    two = analyse_layout(good, [0, 0, 1, 1], grid, H, 0.075, SEP)
    one = analyse_layout(good, [0, 0, 0, 0], grid, H, 0.075, SEP)
    assert two.constraint.ok
    assert two.random_fraction == 0.0
    assert one.random_fraction > 0.0
    assert two.ambiguous_fraction < one.ambiguous_fraction


def test_result_classes_partition_the_ambiguous_cells():
    _, good = _line_layouts()
    grid = PositionGrid.from_room(ROOM, 0.1)
    res = analyse_layout(good, [0] * 4, grid, H, 0.075, SEP)
    assert np.array_equal(res.systematic | res.random, res.ambiguous)
    assert not np.any(res.systematic & res.random)
    assert np.array_equal(res.group >= 0, res.ambiguous)
    # Both cells of every ambiguous pair share a group.
    fp = fingerprints(grid.xy_m, good, [0] * 4, H)
    pairs = ambiguous_pairs(fp, grid.xy_m, 0.075, SEP)
    assert np.array_equal(res.group[pairs[:, 0]], res.group[pairs[:, 1]])
