"""Ranges at which the reflectors reappear via the faces of the room (their multipath ghosts).

A reflector seen via a wall or the ceiling returns at a range that the map predicts: the
image-source method (:mod:`lrp_gym.radar.channel`) mirrors the radar in the faces, and a path
out along image ``a`` and back along image ``b`` has range ``(|a - p| + |b - p|) / 2`` for a
reflector at ``p``, and radial velocity the mean of the two legs' rates. Which pairs matter
depends on the reflector:

- a *retro-directive* type (trihedral, Van Atta) returns the wave the way it came: its strong
  ghosts are out and back via the same face (``a = b``, one bounce each way, range
  ``|a - p|``), and, within its retro lobe (:data:`~lrp_gym.radar.channel.RETRO_LOBE_DEG`),
  direct one way and via a face the other (``a`` the radar, ``b`` a first-order image), which
  happens near a wall, where the image lies close to the radar;
- an *omnidirectional* type (sphere, point, Luneburg lens as modelled) scatters every pair:
  all pairs of images with at most two bounces in all.

With walls of amplitude coefficient ``|Gamma|`` a same-face ghost is ``|Gamma|^4`` below the
direct return in power, so the ghost of a large reflector can pass the tracker's RCS window of
a smaller type: every type's ghosts are predicted for every type's distances.

Images used: every mirror image of the radar with at most two bounces, except those whose leg
at the radar goes down to the floor (the robot's body blocks it in the channel). A ghost is kept where the reflector's
pattern towards both images is more than :data:`MIN_PATTERN_GAIN` of its peak; elsewhere its
range is :data:`FAR_M`, so that no measured distance matches it.
"""

from __future__ import annotations

import itertools

import numpy as np

from lrp_gym.localization._ghost_kernel import ghost_rows_jit
from lrp_gym.radar.channel import RETRO_LOBE_DEG
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.room import Room

#: Pattern gain (relative to the peak) below which a reflector does not return via an image.
MIN_PATTERN_GAIN = 1e-2
#: Range given to a ghost that cannot be seen: beyond any radar's reach.
FAR_M = 1e3

#: Lattice index (n_x, n_y, n_z) of each image with at most two bounces (odd n mirrors
#: in the face at 0 (n = -1) or at L (n = 1), even n adds two opposite faces), without those
#: whose radar-side leg leaves downwards (n_z = -1: the floor next to the radar, blocked by
#: the robot's body as in the channel).
_IMAGES = np.array(
    [
        (nx, ny, nz)
        for nx, ny, nz in itertools.product(range(-2, 3), repeat=3)
        if abs(nx) + abs(ny) + abs(nz) <= 2 and nz != -1
    ]
)
_IMAGES = _IMAGES[np.argsort(np.abs(_IMAGES).sum(axis=1), kind="stable")]  # the radar first
_ORDER = np.abs(_IMAGES).sum(axis=1)
_FIRST = np.flatnonzero(_ORDER == 1)
assert np.array_equal(_FIRST, np.arange(1, 6))  # sorted by order: the radar, then its 5 mirrors
#: Image pairs (a, b) of a retro-directive reflector: same face, or direct and one face.
_PAIRS_RETRO = np.array([(a, a) for a in _FIRST] + [(0, a) for a in _FIRST])
#: Image pairs of an omnidirectional reflector: every pair with one or two bounces.
_PAIRS_OMNI = np.array(
    [
        (a, b)
        for a, b in itertools.combinations_with_replacement(range(len(_IMAGES)), 2)
        if 1 <= _ORDER[a] + _ORDER[b] <= 2
    ]
)


class GhostModel:
    """Predicted ghost ranges and radial velocities of a layout in a shoebox room.

    Parameters
    ----------
    room : Room
        The room whose walls (x = 0, x = L_x, y = 0, y = L_y) and ceiling mirror the radar.
    layout : ReflectorLayout
        The reflectors (positions, axes and types).
    mount_height_m : float
        Radar height above the floor.
    """

    def __init__(self, room: Room, layout: ReflectorLayout, mount_height_m: float) -> None:
        size = np.asarray(room.size_m, dtype=float)
        h = float(mount_height_m)
        self.positions_m = layout.positions_m
        self.axes = layout.axes
        types = [layout.types[t] for t in layout.type_index]
        omni = np.array([t.half_angle_deg is None for t in types])
        self._groups = [
            (np.flatnonzero(~omni), _PAIRS_RETRO, True),
            (np.flatnonzero(omni), _PAIRS_OMNI, False),
        ]
        self._groups = [g for g in self._groups if len(g[0])]
        self._any_omni = bool(omni.any())
        # The patterns fall monotonically with the incidence angle: "gain >= MIN_PATTERN_GAIN"
        # is "cos(incidence) >= a per-reflector threshold", found once on a fine grid.
        cos_grid = np.cos(np.radians(np.linspace(0.0, 180.0, 3601)))
        self._cos_visible = np.array(
            [cos_grid[t.pattern(cos_grid) >= MIN_PATTERN_GAIN].min(initial=2.0) for t in types]
        )
        # A retro lobe of RETRO_LOBE_DEG at -3 dB is MIN_PATTERN_GAIN down at this angle.
        beta_max = RETRO_LOBE_DEG * np.sqrt(-10.0 * np.log10(MIN_PATTERN_GAIN) / 3.0)
        self._cos_beta_min = float(np.cos(np.radians(beta_max)))
        # Image of a coordinate p along an axis of length L: n L + p (n even) or
        # (n + 1) L - p (n odd), as in lrp_gym.radar.image_lattice.image_positions.
        odd = _IMAGES % 2 == 1
        self._sign = np.where(odd[:, :2], -1.0, 1.0)
        self._offset = np.where(odd, _IMAGES + 1, _IMAGES)[:, :2] * size[:2]
        nz = _IMAGES[:, 2]
        self._image_z = np.where(odd[:, 2], (nz + 1) * size[2] - h, nz * size[2] + h)
        #: Use the compiled kernel for float32 (when numba is installed).
        self.use_numba = True
        self._rows = self._row_table()

    def _retro_rows(self, idx, dx, dy, dz, dist, visible, rate, out, rates) -> None:
        """Rows of the retro-directive reflectors ``idx``, in :data:`_PAIRS_RETRO` order (same
        face out and back, then direct one way), from slices instead of gathered pairs."""
        n = dist.shape[-1]
        dtype = dist.dtype.type
        sl = slice(None) if len(idx) == dist.shape[1] else idx
        first = slice(1, 1 + len(_FIRST))
        d0, d1 = dist[0:1, sl], dist[first, sl]
        vis1 = visible[first, sl]
        out.append(np.where(vis1, d1, dtype(FAR_M)).reshape(-1, n))
        # bistatic (direct, face) pairs only within the retro lobe
        cos_beta = dx[first, sl] * dx[0:1, sl] + dy[first, sl] * dy[0:1, sl]
        cos_beta += dz[first, sl] * dz[0:1, sl]
        cos_beta /= d1 * d0
        ok = vis1 & visible[0:1, sl] & (cos_beta >= dtype(self._cos_beta_min))
        out.append(np.where(ok, dtype(0.5) * (d0 + d1), dtype(FAR_M)).reshape(-1, n))
        if rate is not None:
            rates.append(rate[first, sl].reshape(-1, n))
            rates.append((dtype(0.5) * (rate[0:1, sl] + rate[first, sl])).reshape(-1, n))

    def _row_table(self) -> np.ndarray:
        """Each row of :meth:`ranges` as (image a, image b, reflector, retro bistatic), in
        the order the numpy code stacks them (for the compiled kernel)."""
        rows: list[tuple[int, int, int, int]] = []
        for idx, pairs, retro in self._groups:
            if retro:
                rows += [(int(a), int(a), int(m), 0) for a in _FIRST for m in idx]
                rows += [(0, int(a), int(m), 1) for a in _FIRST for m in idx]
            else:
                rows += [(int(a), int(b), int(m), 0) for a, b in pairs for m in idx]
        return np.array(rows, dtype=np.int64).reshape(-1, 4)

    def _ranges_compiled(
        self, xy: np.ndarray, velocity_xy: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """:meth:`ranges` in float32 with the kernel of
        :mod:`~lrp_gym.localization._ghost_kernel` (the same values, bit for bit)."""
        assert ghost_rows_jit is not None
        f32 = np.float32
        xy = np.ascontiguousarray(np.atleast_2d(np.asarray(xy))[:, :2].astype(f32))
        n_img = len(_IMAGES) if self._any_omni else 1 + len(_FIRST)
        dz = (self._image_z[:n_img, None] - self.positions_m[None, :, 2]).astype(f32)
        v = np.zeros((0, 2), dtype=f32)
        if velocity_xy is not None:
            v = np.ascontiguousarray(np.atleast_2d(np.asarray(velocity_xy)).astype(f32))
        out = np.empty((len(self._rows), len(xy)), dtype=f32)
        rates = np.empty_like(out) if velocity_xy is not None else np.empty((0, 0), dtype=f32)
        ghost_rows_jit(
            xy,
            v,
            self._sign[:n_img].astype(f32),
            np.ascontiguousarray(self._offset[:n_img]),
            self.positions_m.astype(f32),
            dz,
            self.axes.astype(f32),
            self._cos_visible.astype(f32),
            f32(self._cos_beta_min),
            self._rows,
            f32(FAR_M),
            out,
            rates,
        )
        return out, (rates if velocity_xy is not None else None)

    @property
    def count(self) -> int:
        """Rows of :meth:`ranges`."""
        return sum(len(pairs) * len(idx) for idx, pairs, _ in self._groups)

    @property
    def row_reflector(self) -> np.ndarray:
        """Layout index (G,) of the reflector of each row of :meth:`ranges`."""
        return self._rows[:, 2].copy()

    @property
    def row_bounces(self) -> np.ndarray:
        """Face bounces (G,) of each row's round trip: 1 or 2."""
        return _ORDER[self._rows[:, 0]] + _ORDER[self._rows[:, 1]]

    @property
    def row_bistatic(self) -> np.ndarray:
        """Whether each row (G,) is a retro-directive reflector's direct-and-face pair."""
        return self._rows[:, 3] == 1

    def ranges(
        self, xy: np.ndarray, velocity_xy: np.ndarray | None = None, dtype=np.float64
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Ghost ranges (G, N) at floor positions (N, 2) (or poses (N, 3)), and their radial
        velocities (G, N) (positive when the range grows) for robot velocities
        ``velocity_xy`` (N, 2), else None. In float32 with numba installed (and
        :attr:`use_numba`), one compiled pass gives the same values."""
        if np.dtype(dtype) == np.float32 and self.use_numba and ghost_rows_jit is not None:
            return self._ranges_compiled(xy, velocity_xy)
        xy = np.atleast_2d(np.asarray(xy))[:, :2].astype(dtype)
        n = len(xy)
        pos = self.positions_m.astype(dtype)
        axes = self.axes.astype(dtype)
        # Retro-directive reflectors need the radar and its first-order images only.
        n_img = len(_IMAGES) if self._any_omni else 1 + len(_FIRST)
        sign = self._sign[:n_img].astype(dtype)
        # Offsets (I, M, N) from each reflector to each image of the radar.
        offset = self._offset[:n_img]
        dx = (sign[:, None, 0:1] * xy[None, None, :, 0] + offset[:, None, 0:1]).astype(dtype) - pos[
            None, :, 0:1
        ]
        dy = (sign[:, None, 1:2] * xy[None, None, :, 1] + offset[:, None, 1:2]).astype(dtype) - pos[
            None, :, 1:2
        ]
        dz = np.broadcast_to(
            (self._image_z[:n_img, None] - self.positions_m[None, :, 2]).astype(dtype)[..., None],
            dx.shape,
        )
        dist = np.sqrt(dx * dx + dy * dy + dz * dz)  # (I, M, N)
        cos_inc = dx * axes[None, :, 0:1] + dy * axes[None, :, 1:2] + dz * axes[None, :, 2:3]
        cos_inc /= dist
        visible = cos_inc >= self._cos_visible.astype(dtype)[None, :, None]
        rate = None
        if velocity_xy is not None:
            v = np.atleast_2d(np.asarray(velocity_xy)).astype(dtype)
            # each image moves at sign * v; a leg's length changes at its projection
            rate = (dx * (sign[:, None, 0:1] * v[None, None, :, 0])) + (
                dy * (sign[:, None, 1:2] * v[None, None, :, 1])
            )
            rate /= dist
        far = dtype(FAR_M)
        out: list[np.ndarray] = []
        rates: list[np.ndarray] = []
        for idx, pairs, retro in self._groups:
            if retro:
                self._retro_rows(idx, dx, dy, dz, dist, visible, rate, out, rates)
                continue
            a, b = pairs[:, 0], pairs[:, 1]
            da, db = dist[a][:, idx], dist[b][:, idx]  # (P, M_g, N)
            ok = visible[a][:, idx] & visible[b][:, idx]
            out.append(np.where(ok, dtype(0.5) * (da + db), far).reshape(-1, n))
            if rate is not None:
                rates.append((dtype(0.5) * (rate[a][:, idx] + rate[b][:, idx])).reshape(-1, n))
        r = np.concatenate(out) if len(out) > 1 else out[0]
        if rate is None:
            return r, None
        return r, (np.concatenate(rates) if len(rates) > 1 else rates[0])
