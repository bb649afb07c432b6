"""The localiser a configuration asks for: AMCL or the histogram filter."""

from __future__ import annotations

from lrp_gym.config import LocalizationConfig, ScenarioConfig
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.grid import GridFilter
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
    """The link budget of ``sensor`` for the localiser of scenario ``cfg``; surveyed
    (:meth:`RadarLink.surveyed`) when ``localization.detection_survey_poses`` asks for it and
    the world needs a visibility model (the survey calibrates its per-reflector
    probabilities; a world whose reflectors are detected everywhere has none)."""
    link = RadarLink.from_sensor(sensor)
    loc = cfg.localization
    if loc.detection_survey_poses == 0 or not loc.reflector_visibility:
        return link
    if not ReflectorVisibility.of(sensor.world, link).needed():
        return link
    rate = lrp_detection_rate(cfg, loc.detection_survey_poses, seed=0)
    return link.surveyed(rate.per_lrp_in_view_rate, loc.detection_probability)
