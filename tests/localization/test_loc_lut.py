import numpy as np
import pytest

from lrp_gym.localization.lut import LookupTable
from lrp_gym.tracking.fingerprint import Fingerprint


@pytest.fixture(scope="module")
def lut(loc_world):
    return LookupTable(loc_world, 0.075, 0.025)


def _cells(world, grid=0.025):
    g = np.arange(grid / 2, 5.0, grid)
    xy = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
    q = np.floor(np.sort(world.true_distances_m(xy), axis=1) / 0.075).astype(int)
    return xy, q


def test_entry_count_is_number_of_unique_quantised_fingerprints(loc_world, lut):
    _, q = _cells(loc_world)
    assert lut.n_entries == len({tuple(r) for r in q})
    assert lut.cell_counts.sum() == len(q)
    assert LookupTable(loc_world, 0.15, 0.025).n_entries < lut.n_entries


def test_exact_fingerprints_of_unambiguous_cells_return_their_centroid(loc_world, lut):
    xy, q = _cells(loc_world)
    keys = {}
    for i, r in enumerate(map(tuple, q)):
        keys.setdefault(r, []).append(i)
    rng = np.random.default_rng(0)
    checked = 0
    for i in rng.choice(len(xy), 300, replace=False):
        entry, _ = lut.lookup(
            Fingerprint.from_true(loc_world.layout, loc_world.radar_position(xy[i]))
        )
        cells = keys[tuple(q[i])]
        np.testing.assert_array_equal(np.floor(lut.keys_m[entry] / 0.075).astype(int), q[i])
        if lut.regions_per_entry[entry] == 1:
            est = lut.query(
                Fingerprint.from_true(loc_world.layout, loc_world.radar_position(xy[i]))
            )
            np.testing.assert_allclose(est.pose[:2], xy[cells].mean(0), atol=1e-9)
            assert np.isinf(est.covariance[2, 2])
            checked += 1
    assert checked > 50


def test_extra_clutter_distance_keeps_the_entry(loc_world, lut):
    rng = np.random.default_rng(1)
    for xy in 0.3 + 4.4 * rng.random((30, 2)):
        fp = Fingerprint.from_true(loc_world.layout, loc_world.radar_position(xy))
        entry, _ = lut.lookup(fp)
        noisy = Fingerprint.from_distances(("A",), [np.r_[fp.distances_m[0], 9.5]])
        assert lut.lookup(noisy)[0] == entry


def test_missing_distance_matches_a_sub_fingerprint_within_half_a_bin(loc_world, lut):
    rng = np.random.default_rng(2)
    for xy in 0.3 + 4.4 * rng.random((40, 2)):
        fp = Fingerprint.from_true(loc_world.layout, loc_world.radar_position(xy))
        z = np.delete(fp.distances_m[0], rng.integers(4))
        entry, resid = lut.lookup(Fingerprint.from_distances(("A",), [z]))
        # Its own bin's sub-key is within half a bin per coordinate: the nearest is no farther.
        assert resid <= 0.5 * 0.075 * np.sqrt(3) + 1e-12


def test_no_distance_gives_the_room_centroid(loc_world, lut):
    est = lut.query(Fingerprint.from_distances(("A",), [np.zeros(0)]))
    np.testing.assert_allclose(est.pose[:2], [2.5, 2.5], atol=0.01)
    assert est.covariance[0, 0] > 1.0
