"""The compiled likelihood kernels against their reference code, on random inputs.

Each kernel replaces numpy code (or a full scan) for speed only: the tests ask for the same
values bit for bit, so that trajectories stay identical.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from lrp_gym.config import load_scenario
from lrp_gym.localization import _map_kernel as mk
from lrp_gym.localization.ghosts import GhostModel
from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.localization.proposal import MeasurementGrid
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world import World

pytestmark = pytest.mark.skipif(mk._binned_jit is None, reason="numba is not installed")


def _random_density_inputs(rng, doppler: bool):
    n, k, n_pos = int(rng.integers(1, 30)), int(rng.integers(1, 70)), int(rng.integers(1, 400))
    z = np.sort(rng.uniform(0.3, 8.0, n))
    half_inv = -0.5 / (0.05**2 + rng.uniform(0.0, 0.01, n))
    extra = rng.uniform(-0.5, 9.0, (k, n_pos)).astype(np.float32)
    near = rng.random((k, n_pos)) < 0.4  # many predicted ranges near a measured one
    extra[near] = (z[rng.integers(0, n, near.sum())] + rng.normal(0, 0.2, near.sum())).astype(
        np.float32
    )
    extra[rng.random((k, n_pos)) < 0.2] = 1e3  # invisible ghosts
    weights = rng.uniform(1e-3, 1e-2, k)
    v = rng.normal(0.0, 0.5, n) if doppler else None
    ev = rng.normal(0.0, 0.5, (k, n_pos)).astype(np.float32) if doppler else None
    return z, half_inv, extra, weights, v, ev


def _full_scan(z, half_inv, extra, weights, v, ev, doppler):
    f32 = np.float32
    out = np.zeros((len(z), extra.shape[1]), dtype=f32)
    vv = np.zeros(0, f32) if v is None else v.astype(f32)
    evv = np.zeros((1, 1), f32) if ev is None else ev
    a, b, c = (f32(x) for x in doppler)
    assert mk._density_jit is not None
    return mk._density_jit(
        z.astype(f32), half_inv.astype(f32), extra, weights.astype(f32), vv, evv, a, b, c, out
    )


@pytest.mark.parametrize("bins_per_window", [1, 3, mk.BINS_PER_WINDOW])
@pytest.mark.parametrize("doppler", [False, True])
def test_binned_map_kernel_equals_the_full_scan_bit_for_bit(doppler, bins_per_window, monkeypatch):
    """Looking up each predicted range's run of candidate distances gives exactly the sums of
    the scan over every distance (same terms past the cutoff, same order), including ranges
    below the smallest distance, far beyond the largest, and right at the cutoff, whatever
    the bins' width."""
    monkeypatch.setattr(mk, "BINS_PER_WINDOW", bins_per_window)
    rng = np.random.default_rng(3)
    coeffs = (2.0, 0.01, -22.0)
    n_terms = 0
    for _ in range(60):
        z, half_inv, extra, weights, v, ev = _random_density_inputs(rng, doppler)
        got = mk.map_return_density(z, half_inv, extra, weights, v, ev, coeffs)
        want = _full_scan(z, half_inv, extra, weights, v, ev, coeffs)
        np.testing.assert_array_equal(got, want)
        n_terms += int(np.count_nonzero(want))
    assert n_terms > 1000  # the inputs do exercise the terms within the cutoff


def test_map_kernel_agrees_with_its_numpy_fallback():
    rng = np.random.default_rng(4)
    for doppler in (False, True):
        z, half_inv, extra, weights, v, ev = _random_density_inputs(rng, doppler)
        got = mk.map_return_density(z, half_inv, extra, weights, v, ev, (2.0, 0.01, -22.0))
        ref = mk.map_return_density(
            z, half_inv, extra, weights, v, ev, (2.0, 0.01, -22.0), use_numba=False
        )
        # The kernel drops terms below exp(CUTOFF) of a term's peak; numpy keeps them.
        np.testing.assert_allclose(got, ref, rtol=1e-4, atol=1e-5 * float(np.sum(weights)))


def _scenario(kind: str):
    cfg = load_scenario("ipin2023-2types")
    if kind == "trihedrals":
        return cfg
    raw = cfg.model_dump()
    raw["reflectors"]["types"]["B"] = {"kind": "sphere", "diameter_m": 0.2}
    if kind == "spheres":
        raw["reflectors"]["types"]["A"] = {"kind": "sphere", "diameter_m": 0.1}
    return load_scenario(raw)


@pytest.mark.parametrize("kind", ["trihedrals", "mixed", "spheres"])
def test_ghost_kernel_equals_the_numpy_ghost_model_bit_for_bit(kind):
    """Retro-directive, omnidirectional and mixed layouts, with and without velocities, at
    positions inside the room and beyond its walls, over several of the kernel's blocks."""
    world = World.from_config(_scenario(kind))
    ghosts = GhostModel(world.room, world.layout, world.mount_height_m)
    rng = np.random.default_rng(5)
    for trial in range(12):
        xy = rng.uniform(-0.5, 5.5, (int(rng.integers(1, 1800)), 2))
        vel = rng.normal(0.0, 0.8, xy.shape).astype(np.float32) if trial % 2 else None
        ghosts.use_numba = True
        got, got_v = ghosts.ranges(xy, vel, np.float32)
        ghosts.use_numba = False
        want, want_v = ghosts.ranges(xy, vel, np.float32)
        assert got.dtype == np.float32 and got.shape == want.shape
        np.testing.assert_array_equal(got, want)
        if vel is None:
            assert got_v is None and want_v is None
        else:
            np.testing.assert_array_equal(got_v, want_v)
    assert np.any(want < 1e3)
    # trihedrals' ghosts are hidden outside their pattern; spheres see every image
    assert np.any(want == 1e3) == (kind != "spheres")


def test_given_map_returns_give_the_same_likelihood_as_computed_ones():
    """AMCL computes the map's predicted returns once per frame and passes them (sliced for
    the lost test's subsample): the log-likelihood is the one computed from scratch."""
    cfg = load_scenario("ipin2023")
    world = World.from_config(cfg)
    model = FingerprintModel.for_world(world, cfg.localization)
    rng = np.random.default_rng(6)
    true = world.radar_position(np.array([1.7, 2.2]))
    dist = np.sort(np.concatenate([world.layout.distances_m(true), rng.uniform(0.9, 4.0, 6)]))
    fp = Fingerprint(
        ("A",), (dist,), (np.full(len(dist), 0.01),), (np.ones(len(dist), bool),),
        (rng.normal(0.0, 0.3, len(dist)),),
    )  # fmt: skip
    xy = rng.uniform(0.3, 4.7, (600, 2))
    vel = rng.normal(0.0, 0.4, (600, 2)).astype(np.float32)
    returns = model.map_returns_at(xy, fp, vel)
    assert returns is not None and returns[1] is not None
    ranges, rates = returns
    np.testing.assert_array_equal(
        model.log_likelihood(xy, fp, velocity_xy=vel, map_ranges=ranges, map_rates=rates),
        model.log_likelihood(xy, fp, velocity_xy=vel),
    )
    sub = np.ascontiguousarray(ranges[:, ::3])
    np.testing.assert_array_equal(
        model.log_likelihood(xy[::3], fp, map_ranges=sub), model.log_likelihood(xy[::3], fp)
    )
    # ranges without their rates are not used where the Doppler term applies
    np.testing.assert_array_equal(
        model.log_likelihood(xy, fp, velocity_xy=vel, map_ranges=ranges + 1.0),
        model.log_likelihood(xy, fp, velocity_xy=vel),
    )


def test_measurement_grid_caches_give_the_likelihood_computed_from_scratch():
    """The lost test's grid keeps the map's returns and the reflectors' ranges at its fixed
    cells: the frame's log-likelihood there is the one computed from scratch."""
    cfg = load_scenario("ipin2023-2types")
    world = World.from_config(cfg)
    model = FingerprintModel.for_world(world, cfg.localization)
    amcl_grid = MeasurementGrid(np.array([5.0, 5.0]), 0.1, lambda xy: np.ones(len(xy), bool))
    rng = np.random.default_rng(8)
    for _ in range(3):
        true = world.radar_position(rng.uniform(0.5, 4.5, 2))
        fp = Fingerprint.from_true(world.layout, true)
        fp = replace(fp, distances_m=tuple(d + rng.normal(0, 0.02, len(d)) for d in fp.distances_m))
        np.testing.assert_array_equal(
            amcl_grid.log_likelihood(model, fp), model.log_likelihood(amcl_grid.centres_m, fp)
        )


def test_structure_kernel_equals_the_numpy_structure_returns_bit_for_bit():
    """The compiled structure rows equal the numpy functions cast to float32, with and without
    velocities (float64 and float32, as the particles' are), at positions inside the room, on
    its walls and corners, and beyond them."""
    from lrp_gym.localization.map_returns import MapReturns
    from lrp_gym.world.structure import structure_ranges_m, structure_velocities_mps

    world = World.from_config(load_scenario("ipin2023"))
    room, h = world.room, world.mount_height_m
    returns = MapReturns(room, world.layout, h, 0.2, 0.0)
    lx, ly, _ = room.size_m
    rng = np.random.default_rng(6)
    for trial in range(10):
        n = int(rng.integers(1, 3000))
        xy = rng.uniform(-1.0, max(lx, ly) + 1.0, (n, 2))
        xy[: min(n, 4)] = [[0.0, 0.0], [lx, ly], [0.0, ly], [lx, 0.0]][: min(n, 4)]
        vel = rng.normal(0.0, 0.8, (n, 2)).astype(np.float32 if trial % 2 else float)
        vel[: min(n, 2)] = 0.0
        want_r = structure_ranges_m(room, h, xy).astype(np.float32)
        want_v = structure_velocities_mps(room, h, xy, vel).astype(np.float32)
        got_r, got_v = returns.ranges(xy, vel, np.float32)
        got_r0, none = returns.ranges(xy, None, np.float32)
        assert none is None
        for got, want in ((got_r, want_r), (got_v, want_v), (got_r0, want_r)):
            np.testing.assert_array_equal(got.view(np.uint32), want.view(np.uint32))
