"""Returns of the room's structure, as opposed to the reflectors': the specular returns of
the room's faces (the radar's own images), the obstacle faces, and point scatterers.

Each function evaluates one kind for one radar position, with the pose-free geometry the
:class:`~lrp_gym.radar.channel.Channel` computed once.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from lrp_gym.radar.image_lattice import image_positions
from lrp_gym.radar.paths import (
    KIND_OBSTACLE_FACE,
    KIND_SCATTERER,
    KIND_SURFACE,
    Paths,
)
from lrp_gym.world.room import Room

FOUR_PI = 4.0 * np.pi

if TYPE_CHECKING:
    from lrp_gym.radar.channel import Channel


def obstacle_faces(room: Room) -> dict[str, np.ndarray]:
    """Faces of the obstacles not lying on a room face: axis, coordinate, sign, bounds."""
    rows = []
    size = room.size_m
    for box in room.obstacles:
        for ax in range(3):
            for sign, c in ((-1.0, box.min_m[ax]), (1.0, box.max_m[ax])):
                if c <= 0.0 or c >= size[ax]:
                    continue
                rows.append((ax, c, sign, box.min_m, box.max_m))
    if not rows:
        return {"axis": np.zeros(0, int)}
    return {
        "axis": np.array([r[0] for r in rows]),
        "coord": np.array([r[1] for r in rows]),
        "sign": np.array([r[2] for r in rows]),
        "lo": np.stack([r[3] for r in rows]),
        "hi": np.stack([r[4] for r in rows]),
    }


def surface_paths(
    ch: Channel, r: np.ndarray, v: np.ndarray, imgs: np.ndarray, img_vel: np.ndarray
) -> Paths:
    """Specular returns of the room's faces: one path per image of the radar (row 0 excluded).

    ``r`` and ``v`` are the radar's position and velocity (3,), ``imgs`` and ``img_vel`` its
    images (I, 3) and their velocities.
    """
    sel = slice(1, None)
    d = r - imgs[sel]
    length = np.linalg.norm(d, axis=1)
    rate = np.einsum("ik,ik->i", d, v - img_vel[sel]) / length
    power = ch.link_w_m2 * ch.image_gamma[sel] ** 2 / ((FOUR_PI * length) ** 2)
    order = ch.image_order[sel]
    if ch.antenna is not None:
        dz_out = imgs[sel, 2] - r[2]
        dz_back = image_positions(r, ch.inverse_indices[sel], ch.room.size_m)[:, 2] - r[2]
        power = power * ch.antenna.gain(dz_out / length) * ch.antenna.gain(dz_back / length)
    ok = ~ch.surface_blocked_by_body[sel] if ch.body_shadowing else None
    if ch.has_obstacles:
        vis = ch.visible(r, imgs[sel], np.arange(1, len(imgs)))
        ok = vis if ok is None else ok & vis
    if ok is not None:
        length, rate, power, order = length[ok], rate[ok], power[ok], order[ok]
    n = len(length)
    return Paths(
        length / 2.0,
        rate / 2.0,
        power,
        np.zeros(n),
        np.full(n, -1),
        order,
        np.full(n, KIND_SURFACE),
    )


def obstacle_face_paths(ch: Channel, r: np.ndarray, v: np.ndarray) -> Paths:
    """First-order returns of obstacle faces whose perpendicular foot from the radar lies on
    the face and in its line of sight."""
    f = ch.faces
    ax = f["axis"]
    dist = f["sign"] * (r[ax] - f["coord"])
    foot = np.broadcast_to(r, (len(ax), 3)).copy()
    foot[np.arange(len(ax)), ax] = f["coord"]
    on_face = np.all((foot >= f["lo"] - 1e-12) & (foot <= f["hi"] + 1e-12), axis=1)
    ok = (dist > 0) & on_face
    ok &= ~ch.room.segments_blocked(np.broadcast_to(r, foot.shape), foot)
    if ch.body_shadowing:
        ok &= foot[:, 2] >= r[2] - 1e-9  # a face seen from above lies below the deck
    dist, rate, dz = dist[ok], (f["sign"] * v[ax])[ok], foot[ok, 2] - r[2]
    g = ch.surfaces.obstacles
    power = ch.link_w_m2 * g**2 / (FOUR_PI * 2.0 * dist) ** 2
    if ch.antenna is not None:
        power = power * ch.antenna.gain(dz / dist) ** 2
    n = len(dist)
    return Paths(
        dist,
        rate,
        power,
        np.zeros(n),
        np.full(n, -1),
        np.ones(n, int),
        np.full(n, KIND_OBSTACLE_FACE),
    )


def scatterer_paths(
    ch: Channel, r: np.ndarray, v: np.ndarray, positions: np.ndarray, rcs_m2: np.ndarray
) -> Paths:
    """Direct returns of point scatterers (K, 3) with RCS ``rcs_m2`` (K,), in line of sight."""
    pos = np.asarray(positions, float).reshape(-1, 3)
    rcs = np.asarray(rcs_m2, float).reshape(-1)
    d = r - pos
    dist = np.linalg.norm(d, axis=1)
    rate = d @ v / dist
    power = ch.link_w_m2 * rcs / (FOUR_PI**3 * dist**4)
    ok = ~ch.room.segments_blocked(np.broadcast_to(r, pos.shape), pos) & (dist > 0)
    if ch.body_shadowing:
        ok &= pos[:, 2] >= r[2] - 1e-9
    if ch.antenna is not None:
        power = power * ch.antenna.gain((pos[:, 2] - r[2]) / np.maximum(dist, 1e-12)) ** 2
    n = int(ok.sum())
    return Paths(
        dist[ok],
        rate[ok],
        power[ok],
        np.zeros(n),
        np.full(n, -2),
        np.zeros(n, int),
        np.full(n, KIND_SCATTERER),
    )
