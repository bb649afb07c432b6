"""Ghosts weighted by how often a survey finds them (return_mix's row counts, the radar link's
ghost weights, MapReturns' mixture weights)."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.config import load_scenario
from lrp_gym.experiments.ghost_evidence import held_out_evidence
from lrp_gym.localization.factory import measured_mixture, radar_link
from lrp_gym.localization.ghosts import GhostModel
from lrp_gym.localization.map_returns import MapReturns
from lrp_gym.localization.reflector_monitor import model_without
from lrp_gym.localization.return_mix import ReturnMix, return_mix
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world.world import World

POSES = 60


def _spheres(**loc):
    """The paper room with its four reflectors spheres (ghosts via every face), fast radar."""
    return load_scenario("ipin2023").with_overrides(
        {
            "radar": {"fidelity": "detections"},
            "reflectors": {"types": {"A": {"kind": "sphere", "diameter_m": 0.2}}},
            "localization": {"return_mix_survey_poses": POSES, **loc},
        }
    )


def _link(cfg):
    world = World.from_config(cfg)
    return world, radar_link(cfg, RadarSensor(world, cfg.radar))


def test_the_survey_finds_each_ghost_where_the_model_predicts_it():
    """Nearly every ghost return of the channel lies within a range bin of one of its
    reflector's predicted ghosts (the two use the same image method)."""
    cfg = _spheres()
    mix = return_mix(cfg, POSES)
    matched = sum(mix.ghost_row_counts)
    assert matched >= 0.95 * mix.ghost * mix.n_returns
    world = World.from_config(cfg)
    assert len(mix.ghost_row_counts) == GhostModel(world.room, world.layout, 0.3).count


def test_one_bounce_ghosts_are_found_more_often_than_two_bounce_ones():
    """Each face bounce costs the wall's reflection loss: per row, ghosts via one face are
    found several times as often as ghosts via two, and a few rows hold most returns."""
    mix = return_mix(_spheres(), POSES)
    counts = np.asarray(mix.ghost_row_counts, dtype=float)
    bounces = np.asarray(mix.ghost_row_bounces)
    assert set(bounces) == {1, 2}
    assert counts[bounces == 1].mean() > 3.0 * counts[bounces == 2].mean()
    top = np.sort(counts)[::-1]
    assert top[: len(top) // 10].sum() > 0.5 * counts.sum()


def test_row_weights_shrink_each_count_towards_its_class():
    counts, classes = (4, 0, 0, 1, 0, 0), (0, 0, 0, 1, 1, 1)
    mix = ReturnMix(0.2, 0.5, 0.2, 0.1, 10, 5, counts, (1, 1, 1, 2, 2, 2), classes)
    w = mix.ghost_row_weights()
    assert w.sum() == pytest.approx(1.0)
    # class means (4 + 1) / 3 and (1 + 1) / 3; each row (count + 1) / (1 + 1 / mean)
    expected = np.array([5 / 1.6, 1 / 1.6, 1 / 1.6, 2 / 2.5, 1 / 2.5, 1 / 2.5])
    np.testing.assert_allclose(w, expected / expected.sum())
    assert np.all(w > 0)


def test_rows_of_one_class_are_alike_but_for_geometry():
    """Classes: same reflector type, bounces and pair kind (the 2 + 2 layout's two trihedral
    types: 2 types x (same face, direct and face) = 4 classes)."""
    cfg = load_scenario("ipin2023-2types").with_overrides({"radar": {"fidelity": "detections"}})
    mix = return_mix(cfg, 5)
    world = World.from_config(cfg)
    ghosts = GhostModel(world.room, world.layout, world.mount_height_m)
    classes = np.asarray(mix.ghost_row_classes)
    assert len(np.unique(classes)) == 4
    for c in np.unique(classes):
        rows = classes == c
        assert len(np.unique(world.layout.type_index[ghosts.row_reflector[rows]])) == 1
        assert len(np.unique(ghosts.row_bistatic[rows])) == 1


def test_map_returns_share_the_ghost_probability_by_the_weights():
    cfg = _spheres()
    world = World.from_config(cfg)
    room, layout, h = world.room, world.layout, world.mount_height_m
    uniform = MapReturns(room, layout, h, 0.3, 0.5)
    n = uniform.ghosts.count
    weights = np.arange(1.0, n + 1.0)
    weighted = MapReturns(room, layout, h, 0.3, 0.5, weights)
    assert weighted.weights.sum() == pytest.approx(0.8)
    ghost_w = weighted.weights[-n:]
    np.testing.assert_allclose(ghost_w, 0.5 * weights / weights.sum())
    np.testing.assert_allclose(weighted.weights[:-n], uniform.weights[:-n])  # the structure
    with pytest.raises(ValueError, match="ghost_weights"):
        MapReturns(room, layout, h, 0.3, 0.5, weights[:-1])


def test_the_link_carries_the_surveyed_weights_when_asked():
    _, link = _link(_spheres())
    mix = return_mix(_spheres(), POSES)
    np.testing.assert_allclose(link.ghost_weights, mix.ghost_row_weights())
    _, off = _link(_spheres(ghost_weights="uniform"))
    assert off.ghost_weights is None
    assert _link(_spheres(return_mix_survey_poses=0))[1].ghost_weights is None
    # the paper room's trihedrals return fewer ghosts than the set share: its mixture stays
    # as set, but its ghosts are weighted too
    paper = load_scenario("ipin2023").with_overrides(
        {"radar": {"fidelity": "detections"}, "localization": {"return_mix_survey_poses": POSES}}
    )
    world, paper_link = _link(paper)
    assert measured_mixture(paper) is paper.localization
    assert len(paper_link.ghost_weights) == GhostModel(world.room, world.layout, 0.3).count


def test_a_reduced_layout_keeps_its_reflectors_ghost_weights_in_row_order():
    """The reflector monitor's model without a reflector: its ghost rows are the full layout's
    rows of the kept reflectors, in order, with their weights."""
    cfg = _spheres()
    world, link = _link(cfg)
    loc = measured_mixture(cfg)
    reduced = model_without(world, loc, (1,), link)
    full = GhostModel(world.room, world.layout, world.mount_height_m)
    kept = full.row_reflector != 1
    xy = np.random.default_rng(0).uniform(0.5, 3.0, size=(20, 2))
    full_m = full.ranges(xy)[0]
    np.testing.assert_array_equal(reduced.map_returns.ghosts.ranges(xy)[0], full_m[kept])
    w = link.ghost_weights[kept]
    ghost_w = reduced.map_returns.weights[-int(kept.sum()) :]
    np.testing.assert_allclose(ghost_w, loc.ghost_probability * w / w.sum())


def test_surveyed_weights_explain_new_frames_better_than_equal_ones():
    """Held out (other poses and noise than the survey's): the radar's frames are more likely
    at the true pose with the surveyed weights, and the true pose stands further above the
    best position more than 1 m away."""
    evidence = held_out_evidence(_spheres(), frames=40)
    assert np.mean(evidence.gain_nats) > 0.3
    assert np.mean(evidence.gain_nats > 0) > 0.6
    surveyed, equal = evidence.margin_nats.mean(axis=0)
    assert surveyed > equal
    with pytest.raises(ValueError, match="ghost_weights"):
        held_out_evidence(_spheres(ghost_weights="uniform"), frames=1)
