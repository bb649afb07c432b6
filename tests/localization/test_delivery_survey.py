"""The delivery survey in every room: a reflector that the radar's link budget detects from
everywhere may still be delivered rarely (masked by the room's stronger returns at similar
ranges), and the likelihood then expects it as rarely as the survey found it."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from lrp_gym.config import load_scenario
from lrp_gym.experiments.ghost_evidence import held_out_margins
from lrp_gym.experiments.scenarios import generated_room
from lrp_gym.localization.factory import measured_mixture, radar_link
from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.localization.visibility import RadarLink, ReflectorVisibility
from lrp_gym.radar.delivery_rate import lrp_detection_rate
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world.world import World

#: Generated room 7: five spheres and no obstacle; every sphere's link budget gives a
#: detection probability >= 0.99 from the whole floor, yet the ceiling's edges and walls at
#: similar ranges mask them: the survey delivers each in a fifth to a half of the frames.
SPHERES_ROOM = 7


@pytest.fixture(scope="module")
def spheres():
    cfg = generated_room(SPHERES_ROOM, {"radar": {"fidelity": "detections"}})
    world = World.from_config(cfg)
    sensor = RadarSensor(world, cfg.radar)
    return cfg, world, sensor, radar_link(cfg, sensor)


def test_a_reflector_delivered_rarely_gets_the_visibility_model(spheres):
    cfg, world, sensor, link = spheres
    plain = RadarLink.from_sensor(sensor)
    assert not ReflectorVisibility.of(world, plain).needed()  # the link budget sees them all
    survey = lrp_detection_rate(cfg, cfg.localization.detection_survey_poses)
    rates = np.asarray(survey.per_lrp_in_view_rate)
    assert np.all(rates < 0.7)
    p_d = cfg.localization.detection_probability
    np.testing.assert_allclose(link.delivery, np.maximum(rates, 0.05) / p_d)
    model = FingerprintModel.for_world(world, measured_mixture(cfg), link)
    assert model.visibility is not None
    # Each sphere's factor from anywhere in view is its share of P_D that the survey found
    # (the likelihood expects it with P_D times this: the surveyed rate, not P_D).
    xy = np.array([[4.0, 5.0], [2.0, 2.0], [7.0, 9.0]])
    expected = model.visibility.exact.detection_probability(xy)
    np.testing.assert_allclose(expected, np.repeat(link.delivery[:, None], 3, axis=1), rtol=0.01)


def test_rooms_delivered_as_expected_keep_the_plain_model():
    """The paper room (both fidelities): every reflector delivered at least as often as
    ``detection_probability`` from everywhere, so no visibility model (the same bits)."""
    for fidelity in ("detections", "signal"):
        cfg = load_scenario("ipin2023").with_overrides({"radar": {"fidelity": fidelity}})
        world = World.from_config(cfg)
        link = radar_link(cfg, RadarSensor(world, cfg.radar))
        assert link.delivery is None
        assert FingerprintModel.for_world(world, cfg.localization, link).visibility is None


def test_the_surveyed_delivery_explains_new_frames_better(spheres):
    """Held out from the survey (other poses and noise): the frames are more likely at the
    true position with the surveyed rates than with every sphere expected at P_D, and the
    truth stands higher above the best wrong position (docs/trust.md, session 28)."""
    cfg, _, _, link = spheres
    evidence = held_out_margins(cfg, (link, replace(link, delivery=None)), frames=20)
    assert evidence.gain_nats.mean() > 1.0
    surveyed, plain = evidence.margin_nats.mean(axis=0)
    assert surveyed > plain + 0.5
