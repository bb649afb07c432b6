"""Ranges at which the reflectors reappear via one face of the room (their multipath ghosts).

A reflector seen via a wall or the ceiling returns at a range that the map predicts: the
image-source method (:mod:`lrp_gym.radar.channel`) mirrors the radar in the face, and a path
out along image ``a`` and back along image ``b`` has range ``(|a - p| + |b - p|) / 2`` for a
reflector at ``p``. Two families matter:

- *same image* (``a = b``, one face): out and back via the same face, range ``|a - p|``. A
  retro-directive reflector (trihedral) returns the wave the way it came, so this is its strong
  ghost; with walls of amplitude coefficient ``|Gamma|`` it is ``|Gamma|^4`` below the direct
  return in power, so the ghost of a large reflector can pass the tracker's RCS window of a
  smaller type.
- *mixed* (``a`` the radar, ``b`` its image): out directly and back via the face, range
  ``(|r - p| + |b - p|) / 2``. An omnidirectional reflector (sphere, point target) returns it
  from anywhere; a retro-directive one only within its retro lobe
  (:data:`~lrp_gym.radar.channel.RETRO_LOBE_DEG`), i.e. near a wall, where the radar's image
  lies close to the radar.

The floor's images are left out: their radar-side leg runs into the robot's body, which the
channel blocks. A ghost is kept where the reflector's pattern towards the image is more than
:data:`MIN_PATTERN_GAIN` of its peak (a downward-facing trihedral does not see the ceiling's
image, a mixed ghost of a retro-directive type outside its retro lobe); elsewhere its range is set to :data:`FAR_M` so that no measured distance matches it.
"""

from __future__ import annotations

import numpy as np

from lrp_gym.radar.channel import RETRO_LOBE_DEG
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.room import Room

#: Pattern gain (relative to the peak) below which a reflector does not return via an image.
MIN_PATTERN_GAIN = 1e-2
#: Range given to a ghost that cannot be seen: beyond any radar's reach.
FAR_M = 1e3


class GhostModel:
    """Predicted ghost ranges and radial velocities of a layout in a shoebox room.

    Parameters
    ----------
    room : Room
        The room whose walls (x = 0, x = L_x, y = 0, y = L_y) and ceiling mirror the radar.
    layout : ReflectorLayout
        The reflectors; all types contribute to every type's ghosts (a large reflector's ghost
        is weak enough to be classified as a smaller type).
    mount_height_m : float
        Radar height above the floor.
    """

    def __init__(self, room: Room, layout: ReflectorLayout, mount_height_m: float) -> None:
        self.size_m = np.asarray(room.size_m, dtype=float)
        self.mount_height_m = float(mount_height_m)
        self.positions_m = layout.positions_m
        self.axes = layout.axes
        types = [layout.types[t] for t in layout.type_index]
        self._omni = np.array([t.half_angle_deg is None for t in types])
        # The patterns fall monotonically with the incidence angle: "gain >= MIN_PATTERN_GAIN"
        # is "cos(incidence) >= a per-reflector threshold", found once on a fine grid.
        cos_grid = np.cos(np.radians(np.linspace(0.0, 180.0, 3601)))
        self._cos_visible = np.array(
            [cos_grid[t.pattern(cos_grid) >= MIN_PATTERN_GAIN].min(initial=2.0) for t in types]
        )
        # A retro lobe of RETRO_LOBE_DEG at -3 dB is MIN_PATTERN_GAIN down at this angle.
        beta_max = RETRO_LOBE_DEG * np.sqrt(-10.0 * np.log10(MIN_PATTERN_GAIN) / 3.0)
        self._cos_beta_min = np.where(self._omni, -2.0, np.cos(np.radians(beta_max)))
        # Per image: sign of (x, y) in the image of (x, y) and its offset, for the four walls
        # and the ceiling. Image z: the radar's height (walls) or 2 H - h (ceiling).
        lx, ly, lz = self.size_m
        self._sign = np.array([[-1, 1], [-1, 1], [1, -1], [1, -1], [1, 1]], dtype=float)
        self._offset = np.array([[0, 0], [2 * lx, 0], [0, 0], [0, 2 * ly], [0, 0]], dtype=float)
        h = self.mount_height_m
        self._image_z = np.array([h, h, h, h, 2.0 * lz - h])

    @property
    def count(self) -> int:
        """Rows of :meth:`ranges`: five same-image and five mixed ghosts per reflector."""
        return 10 * len(self.positions_m)

    def ranges(
        self, xy: np.ndarray, velocity_xy: np.ndarray | None = None, dtype=np.float64
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Ghost ranges (G, N) at floor positions (N, 2) (or poses (N, 3)), and their radial
        velocities (G, N) (positive when the range grows) for robot velocities
        ``velocity_xy`` (N, 2), else None. Rows: same-image ghosts, then mixed ones, each
        image-major ((5, M) flattened)."""
        xy = np.atleast_2d(np.asarray(xy))[:, :2].astype(dtype)
        n = len(xy)
        pos = self.positions_m.astype(dtype)
        axes = self.axes.astype(dtype)
        sign = self._sign.astype(dtype)
        # Offsets (5, M, N) from each reflector to each image of the radar.
        dx = (
            sign[:, None, 0:1] * xy[None, None, :, 0] + dtype(1) * self._offset[:, None, 0:1]
        ).astype(dtype) - pos[None, :, 0:1]
        dy = (sign[:, None, 1:2] * xy[None, None, :, 1] + self._offset[:, None, 1:2]).astype(
            dtype
        ) - pos[None, :, 1:2]
        dz = (self._image_z[:, None] - self.positions_m[None, :, 2]).astype(dtype)[..., None]
        dist = np.sqrt(dx * dx + dy * dy + dz * dz)  # (5, M, N)
        cos_inc = dx * axes[None, :, 0:1] + dy * axes[None, :, 1:2] + dz * axes[None, :, 2:3]
        cos_inc /= dist
        visible = cos_inc >= self._cos_visible.astype(dtype)[None, :, None]
        far = dtype(FAR_M)
        same = np.where(visible, dist, far)
        # Mixed: direct one way, via the face the other. A retro-directive type returns it only
        # within its retro lobe, i.e. near a face, where the image lies close to the radar.
        rx = xy[None, :, 0] - pos[:, 0:1]
        ry = xy[None, :, 1] - pos[:, 1:2]
        rz = dtype(self.mount_height_m) - pos[:, 2:3]
        direct = np.sqrt(rx * rx + ry * ry + rz * rz)  # (M, N)
        cos_beta = dx * rx[None] + dy * ry[None] + dz * rz[None]
        cos_beta /= dist * direct[None]
        lobe_ok = cos_beta >= self._cos_beta_min.astype(dtype)[None, :, None]
        mixed = np.where(visible & lobe_ok, dtype(0.5) * (direct[None] + dist), far)
        out = np.concatenate([same.reshape(-1, n), mixed.reshape(-1, n)])
        if velocity_xy is None:
            return out, None
        v = np.atleast_2d(np.asarray(velocity_xy)).astype(dtype)
        img_vx = sign[:, None, 0:1] * v[None, None, :, 0]  # (5, 1, N): the image's velocity
        img_vy = sign[:, None, 1:2] * v[None, None, :, 1]
        rate = (dx * img_vx + dy * img_vy) / dist
        direct_rate = (rx * v[None, :, 0] + ry * v[None, :, 1]) / direct
        mixed_rate = dtype(0.5) * (direct_rate[None] + rate)
        return out, np.concatenate([rate.reshape(-1, n), mixed_rate.reshape(-1, n)])
