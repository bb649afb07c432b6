"""The localiser a configuration asks for: AMCL or the histogram filter."""

from __future__ import annotations

from lrp_gym.config import LocalizationConfig
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.grid import GridFilter
from lrp_gym.localization.visibility import RadarLink
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world.world import World

#: Anything with AMCL's interface: ``reset``, ``update``, ``update_recovery``, ``estimate``,
#: ``particles``, ``weights``, ``model``, ``cfg``.
Localizer = Amcl | GridFilter


def make_localizer(
    world: World, cfg: LocalizationConfig, radar: RadarSensor | None = None
) -> Localizer:
    """A :class:`GridFilter` for ``cfg.method == "grid"``, else an :class:`Amcl`; with the
    ``radar``, their model predicts each reflector's detection from its link budget.

    With ``method: lut`` AMCL still runs: its cloud identifies the reflectors for the tracker
    and its heading completes the table's position.
    """
    link = None if radar is None else RadarLink.from_sensor(radar)
    if cfg.method == "grid":
        return GridFilter(world, cfg, link)
    return Amcl(world, cfg, link)
