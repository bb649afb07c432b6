import numpy as np
import pytest

from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.localization.sorting import sort_rows_inplace, sort_rows_paired_inplace
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


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("m", [2, 3, 4])
def test_compiled_sorting_network_equals_the_numpy_network_bit_for_bit(m, dtype):
    """Ties and NaNs included: the same sorted values, and the companions permuted alike."""
    rng = np.random.default_rng(10 + m)
    v = rng.random((m, 777)).astype(dtype)
    v[:, ::5] = v[0, ::5]  # ties
    v[rng.random(v.shape) < 0.02] = np.nan
    c = rng.normal(size=v.shape).astype(dtype)
    for use_numba in (True, False):
        got = sort_rows_inplace(v.copy(), use_numba=use_numba)
        np.testing.assert_array_equal(
            got.view(np.uint8), sort_rows_inplace(v.copy(), False).view(np.uint8)
        )
    a, ca, b, cb = v.copy(), c.copy(), v.copy(), c.copy()
    sort_rows_paired_inplace(a, ca, use_numba=True)
    sort_rows_paired_inplace(b, cb, use_numba=False)
    np.testing.assert_array_equal(a.view(np.uint8), b.view(np.uint8))
    np.testing.assert_array_equal(ca.view(np.uint8), cb.view(np.uint8))


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


def _two_type_world():
    from lrp_gym.config import load_scenario
    from lrp_gym.world import World

    return World.from_config(load_scenario("ipin2023-2types"))


def _missed_only(world, xy, fp, p_d=0.8):
    """The negative-information term alone: log L with ``p_d`` minus log L without it."""

    def model(p):
        return FingerprintModel(
            world.layout,
            world.mount_height_m,
            0.075,
            0.2,
            world.fmcw.max_range_m,
            detection_probability=p,
        )

    return model(p_d).log_likelihood(xy, fp, np.float64) - model(0.0).log_likelihood(
        xy, fp, np.float64
    )


def test_missed_reflector_costs_one_minus_detection_probability(loc_world):
    xy = np.array([[2.0, 3.0]])
    fp = Fingerprint.from_true(loc_world.layout, loc_world.radar_position(xy[0]))
    np.testing.assert_allclose(_missed_only(loc_world, xy, fp), 0.0, atol=1e-9)
    d = fp.distances_m[0]
    gaps = np.abs(d[:, None] - d[None, :]) + np.eye(len(d)) * 9.0
    k = int(np.argmax(gaps.min(axis=1)))  # the distance farthest from every other one
    keep = np.arange(len(d)) != k
    one_missed = Fingerprint(("A",), (d[keep],), (fp.variances_m2[0][keep],), (keep[keep],))
    assert gaps[k].min() > 0.3  # the other distances cannot stand in for it
    np.testing.assert_allclose(_missed_only(loc_world, xy, one_missed), np.log(0.2), atol=0.01)


def test_missed_reflector_matched_by_a_distance_of_another_type():
    # A small reflector's weak return often gets the other type's RCS label: the true pose
    # must not pay for that as if the reflector were missing.
    world = _two_type_world()
    xy = np.array([[2.2, 2.6]])
    fp = Fingerprint.from_true(world.layout, world.radar_position(xy[0]))
    assert len(fp.type_names) == 2 and all(len(d) for d in fp.distances_m)
    (d_a, d_b), (v_a, v_b) = fp.distances_m, fp.variances_m2
    relabelled = Fingerprint(
        fp.type_names,
        (np.r_[d_a, d_b[:1]], d_b[1:]),
        (np.r_[v_a, v_b[:1]], v_b[1:]),
        (np.ones(len(d_a) + 1, bool), np.ones(len(d_b) - 1, bool)),
    )
    np.testing.assert_allclose(_missed_only(world, xy, relabelled), 0.0, atol=1e-6)


@pytest.mark.parametrize("speed", [0.0, 0.3, 1.0, 2.0])
def test_clutter_velocity_density_is_a_density_over_the_unambiguous_interval(speed):
    from lrp_gym.localization.likelihood_terms import clutter_velocity_density

    v_max, std = 5.0, 0.15
    uniform = 0.5 / v_max
    v = np.linspace(-v_max, v_max, 200_001)
    density = clutter_velocity_density(speed, std, uniform, v)
    # Static part (box of +-speed blurred by the velocity noise) plus the moving part over
    # +-v_max: the whole integrates to one over the unambiguous interval.
    np.testing.assert_allclose(np.sum(density) * (v[1] - v[0]), 1.0, atol=1e-4)
    assert clutter_velocity_density(speed, std, uniform) == pytest.approx(density[100_000])
    if speed <= 1.0:  # at walking speed far above the uniform density over +-5 m/s
        assert density[100_000] > 3 * uniform


@pytest.mark.parametrize("speed", [0.3, 1.0])
def test_clutter_velocity_density_is_a_chance_match_of_a_static_scatterer(speed):
    # A static scatterer's radial velocity lies anywhere in +-speed (its direction unknown)
    # and is measured with the Doppler noise of a mapped return. The static clutter density
    # is the Doppler term of a pose whose predicted velocity is such a chance value: a chance
    # match then carries no evidence for the pose that makes it (at 0.3 m/s a box of
    # +-(speed + 2 std) was half as dense near zero, and every unmapped scatterer that a wrong
    # pose happened to explain counted for it; docs/robustness.md).
    from lrp_gym.localization.likelihood_terms import MOVING_CLUTTER_SHARE, clutter_velocity_density

    v_max, std = 5.0, 0.15
    uniform = 0.5 / v_max
    v = np.linspace(-speed - 0.5, speed + 0.5, 41)
    u = np.linspace(-speed, speed, 4001)[None, :]  # chance predictions, uniform over +-speed
    chance = np.mean(np.exp(-0.5 * ((v[:, None] - u) / std) ** 2), axis=1) / (
        np.sqrt(2 * np.pi) * std
    )
    static = (clutter_velocity_density(speed, std, uniform, v) - MOVING_CLUTTER_SHARE * uniform) / (
        1 - MOVING_CLUTTER_SHARE
    )
    np.testing.assert_allclose(static, chance, rtol=2e-3, atol=1e-4)
