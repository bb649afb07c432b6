"""Channel features: obstacle faces, hidden reflectors, extra scatterers, body, antenna."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.radar.antenna import ZenithPattern
from lrp_gym.radar.paths import (
    KIND_DIRECT,
    KIND_OBSTACLE_FACE,
    KIND_REFLECTOR_MULTIPATH,
    KIND_SCATTERER,
)
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world import World


def _sensor(cfg, **radar):
    cfg = cfg.with_overrides({"radar": radar}) if radar else cfg
    return RadarSensor(World.from_config(cfg), cfg.radar)


def test_obstacle_face_return_at_its_distance(paper_cfg):
    # a 1 m wide cabinet whose front face (y = 4.0) is 1.2 m ahead of the radar
    box = {"min": [1.0, 4.0, 0.0], "max": [2.0, 4.6, 1.8]}
    cfg = paper_cfg.with_overrides({"room": {"obstacles": [box]}})
    s = _sensor(cfg, noise=False)
    pose = np.array([1.5, 2.8, np.pi / 2])
    vel = np.array([0.0, 0.8])
    p = s.paths(pose, vel)
    face = p.select(p.kind == KIND_OBSTACLE_FACE)
    assert len(face) == 1
    assert face.range_m[0] == pytest.approx(1.2)
    assert face.velocity_mps[0] == pytest.approx(-0.8)  # approaching the face
    # a flat plate seen at normal incidence: Friis over twice the distance, times |Gamma|^2
    g = cfg.room.surfaces.obstacles
    gain = s.channel.antenna.gain(np.array(0.0)) ** 2  # horizontal
    want = s.link_w_m2 * g**2 * gain / (4 * np.pi * 2.4) ** 2
    assert face.power_w[0] == pytest.approx(want, rel=1e-9)
    det = s.measure(pose, vel, np.random.default_rng(0))
    assert np.min(np.abs(det.range_m - 1.2)) < 0.03
    # behind the cabinet only its back face (y = 4.6) shows, not the front one
    p2 = s.paths(np.array([1.5, 4.85, 0.0]), np.zeros(2))
    r2 = p2.select(p2.kind == KIND_OBSTACLE_FACE).range_m
    assert np.any(np.isclose(r2, 0.25)) and not np.any(np.isclose(r2, 0.85))


def test_hidden_removes_every_path_of_that_reflector(paper_cfg):
    s = _sensor(paper_cfg)
    pose, vel = np.array([2.2, 2.9, 0.0]), np.array([0.5, 0.2])
    full = s.paths(pose, vel)
    hidden = np.array([False, True, False, False])
    p = s.paths(pose, vel, hidden=hidden)
    assert np.any(full.reflector_index == 1)
    assert not np.any(p.reflector_index == 1)
    # everything else is unchanged
    assert len(p) == len(full) - int(np.sum(full.reflector_index == 1))
    kinds = set(full.kind[full.reflector_index == 1].tolist())
    assert {KIND_DIRECT, KIND_REFLECTOR_MULTIPATH} <= kinds


def test_extra_scatterer_detected_at_its_range_and_rcs(paper_cfg):
    s = _sensor(paper_cfg, noise=False, antenna_half_power_deg=None)
    pose = np.array([1.0, 1.0, 0.0])
    radar = np.array([1.0, 1.0, paper_cfg.radar.mount_height_m])
    pos = np.array([[2.6, 1.9, 1.7]])  # above the deck, clear of other returns
    rcs_dbsm = 5.0
    dist = float(np.linalg.norm(pos[0] - radar))
    p = s.paths(pose, np.zeros(2), extra_scatterers=(pos, np.array([10 ** (rcs_dbsm / 10)])))
    sc = p.select(p.kind == KIND_SCATTERER)
    assert sc.range_m[0] == pytest.approx(dist)
    det = s.process(p, None)
    j = np.argmin(np.abs(det.range_m - dist))
    assert abs(det.range_m[j] - dist) < 0.01
    assert abs(det.rcs_dbsm[j] - rcs_dbsm) < 1.0
    base = s.process(s.paths(pose, np.zeros(2)), None)
    assert np.min(np.abs(base.range_m - dist)) > 0.05  # it was not there without it


def test_body_blocks_only_from_below(paper_cfg):
    s_on = _sensor(paper_cfg)
    s_off = _sensor(paper_cfg, body_shadowing=False)
    pose = np.array([2.5, 1.5, 0.0])
    below = (np.array([[3.5, 1.5, 0.1]]), np.array([1.0]))
    above = (np.array([[3.5, 1.5, 1.1]]), np.array([1.0]))
    for sens, want_below in ((s_on, 0), (s_off, 1)):
        p = sens.paths(pose, np.zeros(2), extra_scatterers=below)
        assert np.sum(p.kind == KIND_SCATTERER) == want_below
        p = sens.paths(pose, np.zeros(2), extra_scatterers=above)
        assert np.sum(p.kind == KIND_SCATTERER) == 1
    # the direct paths of the reflectors (above the radar) never depend on it
    a, b = s_on.paths(pose, np.zeros(2)), s_off.paths(pose, np.zeros(2))
    np.testing.assert_allclose(
        np.sort(a.range_m[a.kind == KIND_DIRECT]), np.sort(b.range_m[b.kind == KIND_DIRECT])
    )


def test_antenna_pattern_and_rcs_compensation(paper_cfg):
    pat = ZenithPattern(60.0, -20.0)
    assert pat.gain(np.array(1.0)) == pytest.approx(1.0)
    assert pat.gain(np.cos(np.radians(60.0))) == pytest.approx(10**-0.3)
    assert pat.gain(np.array(-1.0)) == pytest.approx(0.01)
    # a reflector's direct path is weighted by the two-way gain towards it, and the RCS
    # estimate undoes it for targets at the reflectors' height
    s = _sensor(paper_cfg, antenna_half_power_deg=60.0)
    s0 = _sensor(paper_cfg, antenna_half_power_deg=None)
    pose = np.array([2.0, 2.0, 0.0])
    a, b = s.paths(pose, np.zeros(2)), s0.paths(pose, np.zeros(2))
    da, db = (x.select(x.kind == KIND_DIRECT) for x in (a, b))
    radar = np.array([2.0, 2.0, paper_cfg.radar.mount_height_m])
    lay = s.world.layout
    for m in range(len(lay)):
        v = lay.positions_m[m] - radar
        g2 = pat.gain(v[2] / np.linalg.norm(v)) ** 2
        pa = da.power_w[da.reflector_index == m][0]
        pb = db.power_w[db.reflector_index == m][0]
        assert pa == pytest.approx(pb * g2, rel=1e-9)
        assert s.rcs_dbsm(pa, np.linalg.norm(v)) == pytest.approx(
            s0.rcs_dbsm(pb, np.linalg.norm(v)), abs=1e-6
        )
