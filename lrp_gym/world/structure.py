"""Ranges of the room's own strong returns, predicted from the map.

An upward-looking radar in a box room sees, besides the LRPs, a few returns whose range follows
from the room alone: the ceiling (range ``H - h``, the same everywhere), the four wall-ceiling
edges (dihedral corners, ``sqrt(d_wall^2 + (H - h)^2)``) and the four walls through the
antenna's side lobes (``d_wall``). Their apparent RCS can be reflector-like, so they pass the
tracker's RCS window. A measurement model that knows them turns them from clutter into evidence
about the position (see :mod:`lrp_gym.localization.likelihood`).
"""

from __future__ import annotations

import numpy as np

from lrp_gym.world.room import Room

N_STRUCTURE_RETURNS = 9


def structure_ranges_m(room: Room, mount_height_m: float, xy: np.ndarray) -> np.ndarray:
    """Predicted ranges (9, N) of ceiling, wall-ceiling edges and walls at positions (N, 2)."""
    xy = np.atleast_2d(np.asarray(xy))
    lx, ly, lz = room.size_m
    x, y = xy[:, 0], xy[:, 1]
    walls = np.stack([x, lx - x, y, ly - y])
    up = lz - mount_height_m
    return np.concatenate([np.full((1, len(x)), up), np.sqrt(walls**2 + up**2), walls])
