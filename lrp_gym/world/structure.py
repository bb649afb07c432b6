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


def structure_ranges_m(room: Room, mount_height_m: float, xy: np.ndarray) -> np.ndarray:
    """Predicted ranges (9, N) of ceiling, wall-ceiling edges and walls at positions (N, 2)."""
    xy = np.atleast_2d(np.asarray(xy))
    lx, ly, lz = room.size_m
    x, y = xy[:, 0], xy[:, 1]
    walls = np.stack([x, lx - x, y, ly - y])
    up = lz - mount_height_m
    return np.concatenate([np.full((1, len(x)), up), np.sqrt(walls**2 + up**2), walls])


def structure_velocities_mps(
    room: Room, mount_height_m: float, xy: np.ndarray, velocity_xy: np.ndarray
) -> np.ndarray:
    """Radial velocities (9, N) of the returns of :func:`structure_ranges_m`, in its order.

    For a radar moving at ``velocity_xy`` (N, 2) over the floor: the ceiling point overhead
    keeps its range (0); a wall's specular point and the wall-ceiling edge's nearest point lie
    along the wall's normal, so they close at the velocity component towards the wall, the edge
    scaled by the horizontal share of its slant range.
    """
    xy = np.atleast_2d(np.asarray(xy))
    velocity_xy = np.atleast_2d(np.asarray(velocity_xy))
    lx, ly, _ = room.size_m
    x, y = xy[:, 0], xy[:, 1]
    vx, vy = velocity_xy[:, 0], velocity_xy[:, 1]
    walls = np.stack([x, lx - x, y, ly - y])
    towards = np.stack([-vx, vx, -vy, vy])  # velocity component towards each wall
    up = room.size_m[2] - mount_height_m
    edge_share = walls / np.sqrt(walls**2 + up**2)
    return np.concatenate([np.zeros((1, len(x))), -towards * edge_share, -towards])
