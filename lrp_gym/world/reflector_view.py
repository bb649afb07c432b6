"""Which reflectors a radar at a floor position has in view, and at what geometry.

A reflector is in view when no obstacle crosses the straight line to it, the incidence on it
is inside its pattern's cutoff, and it is within the radar's range. The radar simulation
applies the same tests to its paths; the localiser's detection model
(:mod:`lrp_gym.localization.visibility`) and the delivery-rate survey
(:mod:`lrp_gym.radar.delivery_rate`) read them from here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.room import Room


@dataclass(frozen=True)
class ReflectorView:
    """Geometry of every (reflector, position) pair; arrays of shape (M, N).

    Attributes
    ----------
    dist_m : ndarray
        Slant distance from the radar to the reflector.
    gain : ndarray
        The reflector's pattern gain (0..1) towards the radar.
    cos_zenith : ndarray
        Cosine of the zenith angle of the direction from the radar to the reflector.
    in_view : ndarray of bool
        Line of sight clear of obstacles, gain above 0 and within range.
    """

    dist_m: np.ndarray
    gain: np.ndarray
    cos_zenith: np.ndarray
    in_view: np.ndarray


def reflector_view(
    room: Room, layout: ReflectorLayout, mount_height_m: float, max_range_m: float, xy
) -> ReflectorView:
    """The view of each reflector from a radar at ``mount_height_m`` above floor positions
    ``xy`` (N, 2)."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    radar = np.empty((xy.shape[0], 3))
    radar[:, :2] = xy
    radar[:, 2] = mount_height_m
    to_radar = radar[None, :, :] - layout.positions_m[:, None, :]  # (M, N, 3)
    dist = np.sqrt(np.einsum("mnk,mnk->mn", to_radar, to_radar))
    cos_inc = np.einsum("mnk,mk->mn", to_radar, layout.axes) / np.maximum(dist, 1e-12)
    gain = np.empty_like(cos_inc)
    for t, rtype in enumerate(layout.types):
        rows = layout.type_index == t
        gain[rows] = rtype.pattern(cos_inc[rows])
    in_view = (dist <= max_range_m) & (gain > 0.0)
    if room.obstacles:
        ends = np.broadcast_to(layout.positions_m[:, None, :], to_radar.shape)
        in_view &= ~room.segments_blocked(np.broadcast_to(radar, to_radar.shape), ends)
    cos_zenith = -to_radar[..., 2] / np.maximum(dist, 1e-12)
    return ReflectorView(dist, gain, cos_zenith, in_view)
