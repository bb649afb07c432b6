"""The localiser a configuration asks for: AMCL or the histogram filter."""

from __future__ import annotations

import json

import numpy as np

from lrp_gym.config import LocalizationConfig, ScenarioConfig
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.grid import GridFilter
from lrp_gym.localization.return_mix import ReturnMix, return_mix
from lrp_gym.localization.visibility import RadarLink, ReflectorVisibility
from lrp_gym.radar.delivery_rate import lrp_detection_rate
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world.world import World

#: Anything with AMCL's interface: ``reset``, ``update``, ``update_recovery``, ``estimate``,
#: ``particles``, ``weights``, ``model``, ``cfg``.
Localizer = Amcl | GridFilter


def make_localizer(
    world: World, cfg: LocalizationConfig, link: RadarLink | None = None
) -> Localizer:
    """A :class:`GridFilter` for ``cfg.method == "grid"``, else an :class:`Amcl`; with the
    radar's ``link`` (:func:`~lrp_gym.localization.visibility.radar_link`), their model
    predicts each reflector's detection.

    With ``method: lut`` AMCL still runs: its cloud identifies the reflectors for the tracker
    and its heading completes the table's position.
    """
    if cfg.method == "grid":
        return GridFilter(world, cfg, link)
    return Amcl(world, cfg, link)


def radar_link(cfg: ScenarioConfig, sensor: RadarSensor) -> RadarLink:
    """The link budget of ``sensor`` for the localiser of scenario ``cfg``.

    Surveyed (:meth:`RadarLink.surveyed`) when ``localization.detection_survey_poses`` asks
    for it and either the survey finds a reflector delivered less often than
    ``localization.detection_probability`` (even one its link budget detects everywhere: the
    room's stronger returns at similar ranges mask it, spheres among the ceiling's edges,
    docs/trust.md session 28) or the world needs a visibility model (the survey calibrates
    it). With the ghosts weighted by the return-mix survey when
    ``localization.return_mix_survey_poses`` asks for one and ``localization.ghost_weights``
    is ``surveyed`` (in every room: unlike the mixture's shares, the weights only say which
    ghosts the radar returns)."""
    link = RadarLink.from_sensor(sensor)
    loc = cfg.localization
    mix = _survey(cfg) if loc.return_mix_survey_poses > 0 else None
    if mix is not None and loc.ghost_weights == "surveyed":
        link = link.with_ghost_weights(mix.ghost_row_weights(), mix.ghost_row_reflector)
    if loc.detection_survey_poses == 0 or not loc.reflector_visibility:
        return link
    surveyed = link.surveyed(_delivery_survey(cfg), loc.detection_probability)
    # The delivery test first: it is free, the floor-grid test of needed() is not.
    if np.any(surveyed.delivery < 1.0) or ReflectorVisibility.of(sensor.world, link).needed():
        return surveyed
    # Delivered as often as the likelihood expects, from everywhere: the plain model.
    return link


def measured_mixture(cfg: ScenarioConfig) -> LocalizationConfig:
    """``cfg``'s localisation settings with the structure and ghost probabilities measured
    by :func:`~lrp_gym.localization.return_mix.return_mix` when
    ``localization.return_mix_survey_poses`` asks for it and the radar returns more ghosts
    than ``ghost_probability`` says (else as set).

    Only up: where omnidirectional reflectors (spheres, Luneburg lenses) see the radar in
    every face, two thirds of the returns are ghosts, and a model that expects a tenth lets
    wrong poses explain them as reflectors (docs/trust.md, session 25). Where the radar
    returns fewer ghosts than set (the paper room's trihedrals), the set mixture stays: with
    the measured one, 2 of 300 episodes under unmapped clutter stuck on a wrong pose (0 with
    the set one; perhaps chance, see docs/trust.md), and the set one is the validated one."""
    loc = cfg.localization
    mix = _ghost_survey(cfg)
    if mix is None:
        return loc
    structure, ghost = mix.map_return_probabilities()
    return loc.model_copy(update={"structure_probability": structure, "ghost_probability": ghost})


def _ghost_survey(cfg: ScenarioConfig) -> ReturnMix | None:
    """``cfg``'s return-mix survey where it applies: ``localization.return_mix_survey_poses``
    asks for it and it finds more ghosts than ``ghost_probability`` says; else None."""
    loc = cfg.localization
    if loc.return_mix_survey_poses == 0:
        return None
    mix = _survey(cfg)
    return mix if mix.map_return_probabilities()[1] > loc.ghost_probability else None


#: Delivery rates in view (M,) per survey inputs (:func:`_delivery_survey`).
_DELIVERY: dict[str, np.ndarray] = {}


def _delivery_survey(cfg: ScenarioConfig) -> np.ndarray:
    """Each reflector's delivered rate in view (:func:`lrp_detection_rate`, the survey's
    ``detection_survey_poses`` frames), computed once per process per survey inputs."""
    key = _survey_key(cfg, cfg.localization.detection_survey_poses)
    if key not in _DELIVERY:
        rate = lrp_detection_rate(cfg, cfg.localization.detection_survey_poses, seed=0)
        _DELIVERY[key] = np.asarray(rate.per_lrp_in_view_rate, dtype=float)
    return _DELIVERY[key]


#: Return-mix surveys per survey inputs: every env of a scenario (each test, each
#: evaluation) would otherwise repeat the same seeded frames.
_MIXTURES: dict[str, ReturnMix] = {}


def _survey(cfg: ScenarioConfig) -> ReturnMix:
    """:func:`return_mix` of ``cfg``, computed once per process for the parts of the scenario
    it reads."""
    key = _survey_key(cfg, cfg.localization.return_mix_survey_poses)
    if key not in _MIXTURES:
        _MIXTURES[key] = return_mix(cfg, cfg.localization.return_mix_survey_poses, seed=0)
    return _MIXTURES[key]


def _survey_key(cfg: ScenarioConfig, n_poses: int) -> str:
    """The parts of ``cfg`` a radar survey of ``n_poses`` frames reads, as a cache key."""
    parts = [cfg.room, cfg.reflectors, cfg.radar, cfg.tracking, cfg.robot]
    return json.dumps([p.model_dump(mode="json") for p in parts] + [n_poses], sort_keys=True)
