"""The ghost model: reflectors seen via a wall or the ceiling, predicted from the map."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.config import load_scenario
from lrp_gym.localization.ghosts import _FIRST, _IMAGES, FAR_M, GhostModel
from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.radar.paths import KIND_DIRECT, KIND_REFLECTOR_MULTIPATH
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world import World


def _spheres():
    cfg = load_scenario("ipin2023").model_dump()
    cfg["reflectors"]["types"] = {"A": {"kind": "sphere", "diameter_m": 0.2}}
    return load_scenario(cfg)


@pytest.mark.parametrize("scenario", ["ipin2023", "ipin2023-2types", "spheres"])
def test_ghost_model_predicts_every_strong_reflector_multipath_of_the_channel(scenario):
    """Every reflector path via the room that the image-source channel produces within 25 dB
    of the strongest direct return has a ghost of the same range and radial velocity
    (retro-directive trihedrals, and omnidirectional spheres with all their bistatic pairs)."""
    cfg = _spheres() if scenario == "spheres" else load_scenario(scenario)
    world = World.from_config(cfg)
    sensor = RadarSensor(world, cfg.radar)
    ghosts = GhostModel(world.room, world.layout, world.mount_height_m)
    rng = np.random.default_rng(1)
    n_strong = 0
    for _ in range(30):
        xy = rng.uniform(0.4, 4.6, 2)
        v = rng.normal(0.0, 1.0, 2)
        paths = sensor.paths(np.array([*xy, 0.0]), v)
        g, gv = ghosts.ranges(xy[None], v[None])
        strongest = paths.power_w[paths.kind == KIND_DIRECT].max()
        strong = (paths.kind == KIND_REFLECTOR_MULTIPATH) & (paths.power_w > strongest * 10**-2.5)
        for r, rv in zip(paths.range_m[strong], paths.velocity_mps[strong], strict=True):
            k = np.argmin(np.abs(g[:, 0] - r))
            assert abs(g[k, 0] - r) < 1e-6
            assert gv[k, 0] == pytest.approx(rv, abs=1e-6)
        n_strong += int(strong.sum())
    assert n_strong >= 15  # there are strong ghosts to check (about one every other frame)


def test_a_downward_trihedral_has_no_ceiling_ghost(paper_world):
    ghosts = GhostModel(paper_world.room, paper_world.layout, paper_world.mount_height_m)
    g, _ = ghosts.ranges(np.array([[2.5, 2.5]]))
    m = len(paper_world.layout)
    same = g[: 5 * m, 0].reshape(5, m)  # out and back via the same face, faces in _FIRST order
    ceiling = [tuple(_IMAGES[a]) for a in _FIRST].index((0, 0, 1))
    assert np.all(same[ceiling] == FAR_M)
    walls = np.delete(same, ceiling, axis=0)
    assert np.all(walls < FAR_M)  # the walls' images are in the trihedrals' pattern


def test_ghost_return_is_evidence_for_the_pose_that_predicts_it(paper_world):
    """A ghost distance added to the true fingerprint costs the true pose less when the model
    knows the ghosts, and the true pose stays the most likely one."""
    true_xy = np.array([4.3, 1.2])
    rng = np.random.default_rng(0)
    xy = np.vstack([true_xy, rng.uniform(0.4, 4.6, (300, 2))])
    fp_true = Fingerprint.from_true(paper_world.layout, paper_world.radar_position(true_xy), 0.02)
    ghosts = GhostModel(paper_world.room, paper_world.layout, paper_world.mount_height_m)
    g, _ = ghosts.ranges(true_xy[None])
    ghost = g[g[:, 0] < 10.0, 0][0]
    fp = Fingerprint.from_distances(
        fp_true.type_names, [np.append(fp_true.distances_m[0], ghost)], 0.02
    )

    def model(gh):
        return FingerprintModel(
            paper_world.layout,
            paper_world.mount_height_m,
            0.075,
            0.2,
            20.0,
            room=paper_world.room,
            structure_probability=0.5,
            ghost_probability=gh,
        )

    def added(gh):
        return model(gh).log_likelihood(xy, fp) - model(gh).log_likelihood(xy, fp_true)

    gain = added(0.2) - added(0.0)
    assert gain[0] > np.median(gain[1:]) + 1.0
    with_gh = model(0.2).log_likelihood(xy, fp)
    assert with_gh[0] > with_gh[1:].max()


def test_structure_and_ghost_probabilities_must_leave_room_for_the_reflectors(paper_world):
    with pytest.raises(ValueError, match="ghost_probability"):
        FingerprintModel(
            paper_world.layout,
            paper_world.mount_height_m,
            0.075,
            0.2,
            paper_world.fmcw.max_range_m,
            room=paper_world.room,
            structure_probability=0.7,
            ghost_probability=0.4,
        )
