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
    assert np.allclose(g[5:9], [1.0, room.size_m[0] - 1.0, 2.0, room.size_m[1] - 2.0])
    lx, ly = room.size_m[:2]
    assert np.allclose(
        g[9:], np.hypot([1.0, lx - 1.0, 1.0, lx - 1.0], [2.0, 2.0, ly - 2.0, ly - 2.0])
    )


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
    rng = np.random.default_rng(0)
    xy = np.vstack([true_xy, rng.uniform(0.4, 4.6, (300, 2))])
    fp_true = Fingerprint.from_true(paper_world.layout, paper_world.radar_position(true_xy), 0.02)
    # Add the true pose's wall-ceiling edge return as an extra (reflector-like) distance.
    edge = structure_ranges_m(paper_world.room, paper_world.mount_height_m, true_xy[None])[1, 0]
    fp = Fingerprint.from_distances(
        fp_true.type_names, [np.append(fp_true.distances_m[0], edge)], 0.02
    )

    def added(s):  # what the extra distance adds to each position's log-likelihood
        model = _model(paper_world, s)
        return model.log_likelihood(xy, fp) - model.log_likelihood(xy, fp_true)

    # Knowing the room turns the extra distance into evidence where it is predicted: it gains
    # more at the true pose than at a typical other one, where it is as good as clutter.
    gain = added(0.4) - added(0.0)
    assert gain[0] > np.median(gain[1:]) + 1.0
    with_s = _model(paper_world, 0.4).log_likelihood(xy, fp)
    assert with_s[0] > with_s[1:].max()


def test_zero_structure_probability_is_the_plain_model(paper_world):
    rng = np.random.default_rng(0)
    xy = rng.uniform(0.5, 4.5, (200, 2))
    fp = Fingerprint.from_distances(("A",), [np.array([2.9, 3.4, 4.4, 5.0, 3.7])], 0.02)
    a = _model(paper_world, 0.0).log_likelihood(xy, fp)
    b = FingerprintModel(
        paper_world.layout, paper_world.mount_height_m, 0.075, 0.2, 20.0
    ).log_likelihood(xy, fp)
    assert np.allclose(a, b)


def test_structure_model_predicts_every_room_path_of_the_channel(paper_cfg, paper_world):
    """Every specular room return that the radar's image-source channel produces (up to two
    bounces, empty shoebox) has a predicted range and radial velocity in the structure model:
    an unpredicted one would be a systematic outlier that favours wrong poses."""
    from lrp_gym.radar.paths import KIND_SURFACE
    from lrp_gym.radar.sensor import RadarSensor
    from lrp_gym.world.structure import structure_velocities_mps

    sensor = RadarSensor(paper_world, paper_cfg.radar)
    rng = np.random.default_rng(3)
    n_paths = 0
    for _ in range(20):
        xy = rng.uniform(0.4, 4.6, 2)
        v = rng.normal(0.0, 1.0, 2)
        paths = sensor.paths(np.array([*xy, 0.0]), v)
        sel = paths.kind == KIND_SURFACE
        assert paths.order[sel].max() <= 2
        g = structure_ranges_m(paper_world.room, paper_world.mount_height_m, xy[None])[:, 0]
        gv = structure_velocities_mps(
            paper_world.room, paper_world.mount_height_m, xy[None], v[None]
        )[:, 0]
        for r, rv in zip(paths.range_m[sel], paths.velocity_mps[sel], strict=True):
            k = np.argmin(np.abs(g - r))
            assert abs(g[k] - r) < 1e-6
            assert gv[k] == pytest.approx(rv, abs=1e-6)
        n_paths += int(sel.sum())
    assert n_paths >= 20 * 8  # ceiling, walls, edges and corners are all in view
