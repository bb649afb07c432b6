import numpy as np
import pytest

from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.localization.sorting import sort_rows_inplace
from lrp_gym.tracking.fingerprint import Fingerprint


def _model(world, c=0.05):
    return FingerprintModel(world.layout, world.mount_height_m, 0.075, c, world.fmcw.max_range_m)


def _grid(n=40):
    rng = np.random.default_rng(5)
    return 0.3 + 4.4 * rng.random((n, 2))


@pytest.mark.parametrize("m", [1, 2, 3, 4, 6])
def test_sorting_network_matches_np_sort(m):
    v = np.random.default_rng(m).random((m, 1000))
    np.testing.assert_array_equal(sort_rows_inplace(v.copy()), np.sort(v, axis=0))


def test_invariant_to_order_of_measured_distances(loc_world):
    model = _model(loc_world)
    xy = _grid()
    fp = Fingerprint.from_true(loc_world.layout, loc_world.radar_position(np.array([2.0, 3.0])))
    rng = np.random.default_rng(0)
    for extra in (0, 1):  # equal counts and the mixture path (one clutter distance)
        d = np.r_[fp.distances_m[0], [2.2] * extra]
        v = np.r_[fp.variances_m2[0], [0.001] * extra]
        ref = model.log_likelihood(xy, Fingerprint(("A",), (d,), (v,), (np.ones(len(d), bool),)))
        perm = rng.permutation(len(d))
        shuffled = Fingerprint(("A",), (d[perm],), (v[perm],), (np.ones(len(d), bool),))
        np.testing.assert_allclose(model.log_likelihood(xy, shuffled), ref, rtol=1e-6)


def test_gaussian_case_matches_closed_form(loc_world):
    model = _model(loc_world, c=0.0)
    xy = _grid()
    z = np.array([2.5, 3.0, 3.3, 4.1])
    var = np.array([0.0, 0.001, 0.002, 0.0])
    fp = Fingerprint(("A",), (z,), (var,), (np.ones(4, bool),))
    e = np.sort(loc_world.true_distances_m(xy), axis=1)
    s2 = 0.075**2 + var
    ref = np.sum(-0.5 * (e - z) ** 2 / s2 - 0.5 * np.log(2 * np.pi * s2), axis=1)
    np.testing.assert_allclose(model.log_likelihood(xy, fp, dtype=np.float64), ref, rtol=1e-12)
    np.testing.assert_allclose(model.log_likelihood(xy, fp), ref, rtol=1e-4, atol=1e-3)


def test_float32_and_float64_agree_with_clutter(loc_world):
    model = _model(loc_world)
    xy = _grid(500)
    fp = Fingerprint.from_true(loc_world.layout, loc_world.radar_position(np.array([1.0, 3.5])))
    np.testing.assert_allclose(
        model.log_likelihood(xy, fp), model.log_likelihood(xy, fp, dtype=np.float64), atol=1e-4
    )


def test_clutter_floor_bounds_the_penalty_of_one_wrong_distance(loc_world):
    model = _model(loc_world, c=0.05)
    xy = np.array([[2.0, 2.0]])
    fp = Fingerprint.from_true(loc_world.layout, loc_world.radar_position(xy[0]))
    good = model.log_likelihood(xy, fp, dtype=np.float64)[0]
    d = fp.distances_m[0].copy()
    d[1] = 15.0
    bad = model.log_likelihood(
        xy, Fingerprint(("A",), (np.sort(d),), fp.variances_m2, fp.fresh), dtype=np.float64
    )[0]
    s2 = 2 * 0.075**2
    peak = 0.95 / np.sqrt(2 * np.pi * s2) + 0.05 / loc_world.fmcw.max_range_m
    floor = 0.05 / loc_world.fmcw.max_range_m
    # The wrong distance costs at most the ratio peak / floor (plus the reordering it causes).
    assert np.isfinite(bad)
    assert good - bad <= 4 * np.log(peak / floor) + 1e-9


@pytest.mark.parametrize("drop", [0, 2])
def test_missed_and_extra_distances_still_peak_near_truth(loc_world, drop):
    model = _model(loc_world)
    true = np.array([3.2, 1.7])
    fp = Fingerprint.from_true(loc_world.layout, loc_world.radar_position(true))
    d = np.delete(fp.distances_m[0], drop)
    for z in (d, np.r_[fp.distances_m[0], 1.9]):
        f = Fingerprint.from_distances(("A",), [z])
        gx = np.arange(0.2, 4.81, 0.05)
        xy = np.stack(np.meshgrid(gx, gx, indexing="ij"), -1).reshape(-1, 2)
        ll = model.log_likelihood(xy, f)
        assert ll[np.hypot(*(xy - true).T) < 0.05].max() >= np.quantile(ll, 0.995)


def test_unknown_type_is_ignored(loc_world):
    model = _model(loc_world)
    xy = _grid()
    fp = Fingerprint.from_true(loc_world.layout, loc_world.radar_position(np.array([2.0, 3.0])))
    more = Fingerprint(
        ("A", "Z"),
        (fp.distances_m[0], np.array([1.0])),
        (fp.variances_m2[0], np.array([0.0])),
        (fp.fresh[0], np.array([True])),
    )
    np.testing.assert_allclose(model.log_likelihood(xy, more), model.log_likelihood(xy, fp))
