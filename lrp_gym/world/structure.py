"""Ranges of the room's own strong returns, predicted from the map.

An upward-looking radar in a box room sees, besides the LRPs, a few returns whose range follows
from the room alone: the ceiling (range ``H - h``, the same everywhere), the four wall-ceiling
edges (dihedral corners, ``sqrt(d_wall^2 + (H - h)^2)``), the four walls through the
antenna's side lobes (``d_wall``) and the four vertical wall-wall corners (dihedrals whose
image lies at the radar's height, range = the horizontal distance to the corner). These are
all the specular paths of up to two bounces that do not run through the robot (the floor's
are blocked by its body, a back-and-forth between parallel faces retraces through it). Their apparent RCS can be reflector-like, so they pass the
tracker's RCS window. A measurement model that knows them turns them from clutter into evidence
about the position (see :mod:`lrp_gym.localization.likelihood`).
"""

from __future__ import annotations

import numpy as np

from lrp_gym.world.room import Room

N_STRUCTURE_RETURNS = 13


def _corner_offsets(room: Room, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal offsets (4, N) from positions (N, 2) to the room's vertical corners."""
    lx, ly, _ = room.size_m
    cx = np.array([0.0, lx, 0.0, lx])[:, None]
    cy = np.array([0.0, 0.0, ly, ly])[:, None]
    return cx - xy[:, 0], cy - xy[:, 1]


def structure_ranges_m(room: Room, mount_height_m: float, xy: np.ndarray) -> np.ndarray:
    """Predicted ranges (13, N) at positions (N, 2): ceiling, the four wall-ceiling edges,
    the four walls (x = 0, x = L_x, y = 0, y = L_y) and the four vertical corners ((0, 0),
    (L_x, 0), (0, L_y), (L_x, L_y))."""
    xy = np.atleast_2d(np.asarray(xy))
    lx, ly, lz = room.size_m
    x, y = xy[:, 0], xy[:, 1]
    walls = np.stack([x, lx - x, y, ly - y])
    up = lz - mount_height_m
    dx, dy = _corner_offsets(room, xy)
    return np.concatenate(
        [np.full((1, len(x)), up), np.sqrt(walls**2 + up**2), walls, np.hypot(dx, dy)]
    )


def structure_velocities_mps(
    room: Room, mount_height_m: float, xy: np.ndarray, velocity_xy: np.ndarray
) -> np.ndarray:
    """Radial velocities (13, N) of the returns of :func:`structure_ranges_m`, in its order.

    For a radar moving at ``velocity_xy`` (N, 2) over the floor: the ceiling point overhead
    keeps its range (0); a wall's specular point and the wall-ceiling edge's nearest point lie
    along the wall's normal, so they close at the velocity component towards the wall, the edge
    scaled by the horizontal share of its slant range; a vertical corner is a fixed point at
    the radar's height, closing at the velocity component towards it.
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
    dx, dy = _corner_offsets(room, xy)
    corner = -(vx * dx + vy * dy) / np.maximum(np.hypot(dx, dy), 1e-9)
    return np.concatenate([np.zeros((1, len(x))), -towards * edge_share, -towards, corner])
