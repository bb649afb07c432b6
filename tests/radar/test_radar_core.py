"""Analytic checks of the radar channel, front end, processing and sensor."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.radar.cfar import Cfar2D
from lrp_gym.radar.frontend import beat_cube
from lrp_gym.radar.image_lattice import image_positions, lattice_indices
from lrp_gym.radar.paths import KIND_DIRECT, KIND_SURFACE
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world import World


def _sensor(cfg, **radar):
    cfg = cfg.with_overrides({"radar": radar}) if radar else cfg
    return RadarSensor(World.from_config(cfg), cfg.radar)


def _single(sensor, r, v, p_w=1e-10):
    fm = sensor.fmcw
    cube = beat_cube(fm, np.array([r]), np.array([v]), np.array([p_w]), np.array([0.3]))
    return sensor.processor.power_map(cube)


def test_lattice_counts_and_positions():
    idx = lattice_indices(2)
    orders = np.abs(idx).sum(axis=1)
    assert (orders == 1).sum() == 6 and (orders == 2).sum() == 18
    size = np.array([5.0, 4.0, 3.0])
    p = np.array([1.0, 1.5, 0.5])
    img = image_positions(p, idx, size)
    # order 1: mirrors in the six faces
    want1 = {
        (-1.0, 1.5, 0.5),
        (9.0, 1.5, 0.5),
        (1.0, -1.5, 0.5),
        (1.0, 6.5, 0.5),
        (1.0, 1.5, -0.5),
        (1.0, 1.5, 5.5),
    }
    assert {tuple(np.round(x, 9)) for x in img[orders == 1]} == want1
    # order 2 along x: x + 2L and x - 2L; corner x=0,y=0: (-x, -y, z)
    got2 = {tuple(np.round(x, 9)) for x in img[orders == 2]}
    assert {(11.0, 1.5, 0.5), (-9.0, 1.5, 0.5), (-1.0, -1.5, 0.5)} <= got2


def test_ceiling_and_floor_returns(paper_cfg):
    s = _sensor(paper_cfg, body_shadowing=False)
    p = s.paths(np.array([2.0, 2.5, 0.0]), np.zeros(2))
    surf = p.select((p.kind == KIND_SURFACE) & (p.order == 1))
    assert np.any(np.isclose(surf.range_m, 4.0 - 0.3))  # ceiling
    assert np.any(np.isclose(surf.range_m, 0.3))  # floor
    assert np.any(np.isclose(surf.range_m, 2.0))  # wall x=0
    # the robot under the radar hides the floor and the echo between parallel faces
    p = _sensor(paper_cfg).paths(np.array([2.0, 2.5, 0.0]), np.zeros(2))
    surf = p.select(p.kind == KIND_SURFACE)
    assert np.any(np.isclose(surf.range_m, 4.0 - 0.3))
    assert not np.any(np.isclose(surf.range_m, 0.3))
    assert not np.any(np.isclose(surf.range_m, 5.0))  # x=0 <-> x=5 and y=0 <-> y=5
    assert not np.any(np.isclose(surf.range_m, 4.0))  # floor <-> ceiling


def test_obstacle_shadows_direct_path(paper_cfg):
    refl = np.array(paper_cfg.reflectors.layout[0].position)
    pose = np.array([2.5, 2.5, 0.0])
    radar = np.array([2.5, 2.5, paper_cfg.radar.mount_height_m])
    # a thin pillar across the line of sight, halfway between radar and reflector
    mid = radar + 0.5 * (refl - radar)
    box = {"min": [mid[0] - 0.1, mid[1] - 0.1, 0.0], "max": [mid[0] + 0.1, mid[1] + 0.1, 3.5]}
    cfg = paper_cfg.with_overrides({"room": {"obstacles": [box]}})
    p = _sensor(cfg).paths(pose, np.zeros(2))
    direct = p.select(p.kind == KIND_DIRECT)
    assert 0 not in direct.reflector_index
    assert {1, 2, 3} <= set(direct.reflector_index.tolist())
    p0 = _sensor(paper_cfg).paths(pose, np.zeros(2))
    d0 = p0.select((p0.kind == KIND_DIRECT) & (p0.reflector_index == 0))
    assert np.isclose(d0.range_m[0], np.linalg.norm(radar - refl))


@pytest.mark.parametrize("r", [0.6, 3.337, 7.9, 12.41, 18.5])
@pytest.mark.parametrize("v", [-5.5, -1.234, 0.0, 2.05, 5.4])
def test_single_target_cell_and_interpolation(paper_cfg, r, v):
    s = _sensor(paper_cfg, noise=False)
    pm = _single(s, r, v)
    fm = s.fmcw
    i, k = np.unravel_index(np.argmax(pm), pm.shape)
    coupling = 2 * v * fm.chirp_period_s / fm.wavelength_m
    assert abs(i - (r / fm.range_resolution_m + coupling)) <= 0.5 + 1e-9
    assert abs(k - (v / fm.velocity_resolution_mps + fm.chirps_per_frame // 2)) <= 0.5 + 1e-9
    pk = s.processor.peaks(pm, floor=1e-30)
    j = np.argmax(pk.peak_power)
    vel = (pk.doppler_bin[j] - 16) * fm.velocity_resolution_mps
    rng_m = (
        pk.range_bin[j] - 2 * vel * fm.chirp_period_s / fm.wavelength_m
    ) * fm.range_resolution_m
    assert abs(rng_m - r) < 0.01
    assert abs(vel - v) < 0.01


@pytest.mark.parametrize("window", ["hann", "rect"])
def test_two_targets_resolution(paper_cfg, window):
    s = _sensor(paper_cfg, noise=False, window=window)
    fm, proc = s.fmcw, s.processor
    cell = proc.resolution_cell_m
    for sep, want in ((1.25 * cell, 2), (0.5 * cell, 1)):
        r = np.array([5.0, 5.0 + sep])
        # in phase at the window centre: the hardest case to resolve, the easiest to merge
        phase = -np.pi * r / fm.range_resolution_m
        cube = beat_cube(fm, r, np.zeros(2), np.full(2, 1e-10), phase)
        pk = proc.peaks(proc.power_map(cube), floor=1e-30)
        strong = pk.peak_power > 1e-3 * pk.peak_power.max()
        assert strong.sum() == want, (sep, pk.range_bin[strong])


@pytest.mark.parametrize("method", ["CA", "SO", "GO", "OS"])
def test_cfar_false_alarm_rate(method):
    cfar = Cfar2D(method, (2, 1), (8, 3), 1e-3, 0.75)
    rng = np.random.default_rng(3)
    maps = rng.exponential(1.0, (40, 256, 32))
    fa = np.mean([cfar.detect(m).mean() for m in maps])
    assert 0.5e-3 < fa < 2e-3, fa


def test_rcs_calibration_across_range(paper_cfg):
    s = _sensor(paper_cfg, noise=False, antenna_half_power_deg=None)
    fm = s.fmcw
    rng = np.random.default_rng(0)
    for r in np.linspace(0.5, fm.max_range_m - 0.2, 25):
        v = rng.uniform(-5, 5)
        p_w = s.link_w_m2 / ((4 * np.pi) ** 3 * r**4)  # 0 dBsm
        cube = beat_cube(fm, np.array([r]), np.array([v]), np.array([p_w]), np.array([1.0]))
        pk = s.processor.peaks(s.processor.power_map(cube), floor=1e-30)
        j = np.argmax(pk.peak_power)
        rcs = s.rcs_dbsm(pk.power_at_antenna_w[j], r)
        assert abs(rcs) < 1.0, (r, rcs)


def test_sensor_deterministic_and_detects_lrp(paper_cfg):
    s = _sensor(paper_cfg)
    pose, vel = np.array([2.5, 2.5, 0.0]), np.array([0.5, 0.0])
    a = s.measure(pose, vel, np.random.default_rng(7))
    b = s.measure(pose, vel, np.random.default_rng(7))
    np.testing.assert_array_equal(a.range_m, b.range_m)
    np.testing.assert_array_equal(a.rcs_dbsm, b.rcs_dbsm)
    assert s.last_map_db.shape == (256, 32)
    assert np.all(a.range_m >= paper_cfg.radar.min_range_m)
