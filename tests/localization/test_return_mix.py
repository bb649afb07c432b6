"""The measured mixture of reflector-like returns (lrp_gym.localization.return_mix) and the
localiser settings built from it."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.config import load_scenario
from lrp_gym.localization.factory import measured_mixture
from lrp_gym.localization.return_mix import ReturnMix, return_mix

POSES = 60


def _fast(name: str, **over):
    """The scenario at the detections fidelity (the survey is the same chain, faster)."""
    return load_scenario(name).with_overrides({"radar": {"fidelity": "detections"}, **over})


def _kind(kind: str, **size) -> dict:
    """The paper room's four reflectors, all of one kind."""
    return {"reflectors": {"types": {"A": {"kind": kind, **size}}}}


def test_shares_sum_to_one_and_repeat_with_the_seed():
    cfg = _fast("ipin2023")
    mix = return_mix(cfg, POSES, seed=3)
    assert mix.n_returns > POSES  # several reflector-like returns per frame
    total = mix.direct + mix.ghost + mix.structure + mix.other
    assert total == pytest.approx(1.0)
    assert return_mix(cfg, POSES, seed=3) == mix
    assert return_mix(cfg, POSES, seed=4) != mix


def test_paper_room_is_mostly_room_returns_and_reflectors():
    """The paper room's trihedrals: a third of the returns direct, most of the rest the room,
    few ghosts (a trihedral returns the wave the way it came)."""
    mix = return_mix(_fast("ipin2023"), POSES)
    assert 0.2 < mix.direct < 0.5
    assert 0.45 < mix.structure < 0.75
    assert mix.ghost < 0.1


def test_spheres_see_the_radar_in_every_face():
    """Omnidirectional scatterers return via every face: ghosts outnumber direct returns,
    where trihedrals of the same RCS class in the same room give few."""
    spheres = return_mix(_fast("ipin2023", **_kind("sphere", diameter_m=0.2)), POSES)
    assert spheres.ghost > 0.35
    assert spheres.ghost > 2.0 * spheres.direct


def test_absorbing_faces_leave_no_ghosts():
    """With every face an absorber, no path bounces: only direct returns remain."""
    absorbing = {"ceiling": 0.0, "floor": 0.0, "walls": 0.0, "obstacles": 0.0}
    cfg = _fast("ipin2023", **_kind("sphere", diameter_m=0.2), room={"surfaces": absorbing})
    mix = return_mix(cfg, POSES)
    assert mix.ghost == 0.0
    assert mix.direct > 0.9


def test_map_return_probabilities_are_shares_of_the_mapped_returns():
    mix = ReturnMix(direct=0.2, ghost=0.5, structure=0.2, other=0.1, n_returns=100, n_poses=10)
    structure, ghost = mix.map_return_probabilities()
    assert structure == pytest.approx(0.2 / 0.9)
    assert ghost == pytest.approx(0.5 / 0.9)
    none = ReturnMix(direct=1.0, ghost=0.0, structure=0.0, other=0.0, n_returns=5, n_poses=5)
    # a kind is kept: a few hundred frames cannot prove it absent
    assert none.map_return_probabilities(floor=0.02) == (0.02, 0.02)


def test_measured_mixture_replaces_the_set_probabilities_only_when_asked():
    cfg = _fast("ipin2023", **_kind("sphere", diameter_m=0.2))
    off = cfg.with_overrides({"localization": {"return_mix_survey_poses": 0}})
    assert measured_mixture(off) is off.localization  # 0 poses: as set
    asked = cfg.with_overrides({"localization": {"return_mix_survey_poses": POSES}})
    loc = measured_mixture(asked)
    expected = return_mix(asked, POSES, seed=0).map_return_probabilities()
    assert (loc.structure_probability, loc.ghost_probability) == pytest.approx(expected)
    assert loc.ghost_probability > cfg.localization.ghost_probability


def test_a_room_with_fewer_ghosts_than_set_keeps_the_set_mixture():
    """The paper room's trihedrals return fewer ghosts than the set share: the localiser's
    settings are the scenario's own object (its trajectories unchanged)."""
    cfg = _fast("ipin2023", localization={"return_mix_survey_poses": POSES})
    measured_ghost = return_mix(cfg, POSES, seed=0).map_return_probabilities()[1]
    assert measured_ghost < cfg.localization.ghost_probability
    assert measured_mixture(cfg) is cfg.localization


def test_the_env_localiser_weighs_with_the_measured_mixture():
    import gymnasium as gym

    import lrp_gym  # noqa: F401

    over = {"localization": {"return_mix_survey_poses": POSES}, **_kind("sphere", diameter_m=0.2)}
    env = gym.make("LRPRadarNavFast-v0", overrides=over)
    model = env.unwrapped.core.stacks[0].localizer.model
    cfg = env.unwrapped.cfg
    expected = return_mix(cfg, POSES, seed=0).map_return_probabilities()
    assert (model.structure_probability, model.ghost_probability) == pytest.approx(expected)
    assert np.isclose(model.map_returns.probability, sum(expected))
    env.close()


def test_bad_survey_size_is_refused():
    with pytest.raises(ValueError, match="n_poses"):
        return_mix(_fast("ipin2023"), 0)
    from lrp_gym.config.base import ScenarioError

    with pytest.raises(ScenarioError, match="return_mix_survey_poses"):
        _fast("ipin2023", localization={"return_mix_survey_poses": -1})


def test_the_survey_is_kept_per_scenario_not_reused_for_another_room():
    cfg = _fast("ipin2023", localization={"return_mix_survey_poses": POSES})
    first = measured_mixture(cfg)
    assert measured_mixture(cfg) == first  # the kept survey
    spheres = cfg.with_overrides(_kind("sphere", diameter_m=0.2))
    assert measured_mixture(spheres).ghost_probability > 2 * first.ghost_probability
