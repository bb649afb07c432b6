"""Propagation paths in the shoebox room by the image-source method (monostatic radar).

What is modelled
----------------
- Direct returns of the reflectors (radar equation with the reflector's incidence pattern).
- Reflector returns via surface bounces: out along the image ``a`` of the radar, back along
  image ``b`` (orders ``i + j <= K``). The reciprocal pair (a, b) / (b, a) has the same length,
  Doppler and phase, so it is stored once with twice the amplitude (four times the power).
  For retro-directive types (those with a finite pattern half angle) the bistatic pair a != b
  is further attenuated by a Gaussian retro lobe of :data:`RETRO_LOBE_DEG` in the bistatic
  angle; omnidirectional types keep ``sqrt(sigma_a sigma_b)``.
- Specular returns of the room's faces: the images of the radar itself (shoebox lattice,
  order 1 -> 6, order 2 -> 18 images in 3-D), Friis form with the round-trip length.
- First-order specular returns of obstacle faces where the foot of the perpendicular from the
  radar lies on the face.
- Shadowing: a path is dropped when one of its real (folded) segments crosses an obstacle.
- Robot body (``body_shadowing``): the radar sits on the robot's top deck, so a leg that
  leaves or reaches the radar from below its horizontal plane runs into the robot (this drops
  the floor return under the robot and every path whose bounce next to the radar is on the
  floor), and a path that retraces itself through the radar (the back-and-forth echo between
  two parallel faces, image indices along one axis only with an even count) is blocked by the
  radar and robot it passes through. For ``max_order <= 2`` these are all the paths through
  the robot; interior legs of higher orders are not tested against the body.
- Antenna (``antenna``): an optional zenith pattern (:mod:`lrp_gym.radar.antenna`) weighs each
  path by the gains of its departing and arriving legs.

Surfaces are smooth mirrors (no diffuse scattering); each bounce multiplies the amplitude by
the face's |Gamma| and adds a phase of pi.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from lrp_gym.radar.antenna import ZenithPattern
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.room import Room

#: -3 dB bistatic half angle of a retro-directive reflector's return lobe.
RETRO_LOBE_DEG = 5.0

KIND_DIRECT = 0
KIND_REFLECTOR_MULTIPATH = 1
KIND_SURFACE = 2
KIND_OBSTACLE_FACE = 3
KIND_SCATTERER = 4
KIND_NAMES = ("direct", "reflector_multipath", "surface", "obstacle_face", "scatterer")

FOUR_PI = 4.0 * np.pi


def _f(a=()) -> np.ndarray:
    return np.asarray(a, dtype=float).reshape(-1)


@dataclass(frozen=True)
class Paths:
    """Propagation paths of one radar frame (all arrays of shape (P,)).

    Attributes
    ----------
    range_m : ndarray
        Half the round-trip path length.
    velocity_mps : ndarray
        Rate of change of ``range_m`` (positive when receding).
    power_w : ndarray
        Received power at the antenna port.
    phase_rad : ndarray
        Carrier phase of the return, ``4 pi range / lambda + pi * bounces``.
    reflector_index : ndarray of int
        Index into the layout for reflector paths, ``-1`` for surfaces and ``-2`` for extra
        scatterers.
    order : ndarray of int
        Number of surface bounces on the path.
    kind : ndarray of int
        One of the ``KIND_*`` codes (see :data:`KIND_NAMES`).
    """

    range_m: np.ndarray = field(default_factory=_f)
    velocity_mps: np.ndarray = field(default_factory=_f)
    power_w: np.ndarray = field(default_factory=_f)
    phase_rad: np.ndarray = field(default_factory=_f)
    reflector_index: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    order: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    kind: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    def __len__(self) -> int:
        return len(self.range_m)

    def select(self, mask_or_index) -> Paths:
        """A subset of the paths."""
        return Paths(*(getattr(self, k)[mask_or_index] for k in _FIELDS))

    @staticmethod
    def concatenate(parts: list[Paths]) -> Paths:
        if not parts:
            return Paths()
        return Paths(*(np.concatenate([getattr(p, k) for p in parts]) for k in _FIELDS))


_FIELDS = ("range_m", "velocity_mps", "power_w", "phase_rad", "reflector_index", "order", "kind")


def lattice_indices(order: int, dims: int = 3) -> np.ndarray:
    """Image indices ``n`` (rows of shape (dims,)) with ``1 <= sum |n_i| <= order``.

    Sorted by order; the count per order in 3-D is 6 for order 1 and 18 for order 2
    (the shoebox lattice of pyroomacoustics).
    """
    r = np.arange(-order, order + 1)
    grid = np.stack(np.meshgrid(*([r] * dims), indexing="ij"), axis=-1).reshape(-1, dims)
    o = np.abs(grid).sum(axis=1)
    keep = (o >= 1) & (o <= order)
    grid, o = grid[keep], o[keep]
    return grid[np.argsort(o, kind="stable")]


def image_positions(points: np.ndarray, indices: np.ndarray, size_m: np.ndarray) -> np.ndarray:
    """Images (..., I, 3) of points (..., 3) for lattice indices (I, 3) in a box ``[0, L]``.

    Along each axis the image for index ``n`` is ``n L + p`` (n even) or ``(n + 1) L - p``
    (n odd): ``n = -1`` mirrors in the face at 0, ``n = 1`` in the face at ``L``.
    """
    p = np.asarray(points, float)[..., None, :]
    n = indices
    odd = (n % 2) != 0
    return np.where(odd, (n + 1) * size_m - p, n * size_m + p)


def lattice_gamma(indices: np.ndarray, face_gamma: np.ndarray) -> np.ndarray:
    """Product of the amplitude reflection coefficients along each image's bounces.

    ``face_gamma`` is ordered x=0, x=L, y=0, y=L, z=0, z=L. A positive index ``n`` on an axis
    bounces ``ceil(n/2)`` times on the face at L and ``floor(n/2)`` times on the face at 0;
    a negative index the other way round.
    """
    a = np.abs(indices)
    first = (a + 1) // 2
    second = a // 2
    pos = indices > 0
    hits_hi = np.where(pos, first, second)
    hits_lo = np.where(pos, second, first)
    lo = face_gamma[0::2]
    hi = face_gamma[1::2]
    return np.prod(lo**hits_lo * hi**hits_hi, axis=-1)


def _crossing_planes(indices: np.ndarray, size_m: np.ndarray, order: int):
    """Planes crossed by the unfolded line from cell 0 to cell ``n``: axis, coordinate, valid.

    Shapes (I, K); invalid entries are padding.
    """
    n_img = len(indices)
    axis = np.zeros((n_img, max(order, 1)), dtype=int)
    coord = np.zeros((n_img, max(order, 1)))
    valid = np.zeros((n_img, max(order, 1)), dtype=bool)
    for i, n in enumerate(indices):
        j = 0
        for ax in range(3):
            ks = range(1, n[ax] + 1) if n[ax] > 0 else range(0, n[ax], -1)
            for k in ks:
                axis[i, j], coord[i, j], valid[i, j] = ax, k * size_m[ax], True
                j += 1
    return axis, coord, valid


def _fold(x: np.ndarray, size_m: np.ndarray) -> np.ndarray:
    """Fold unfolded (lattice) coordinates back into the room."""
    y = np.mod(x, 2.0 * size_m)
    return np.where(y > size_m, 2.0 * size_m - y, y)


class Channel:
    """Image-source channel of a room with reflectors, for a monostatic radar.

    Pose-independent geometry (image lattice, bounce coefficients, path pairs, obstacle
    faces) is computed once here; :meth:`paths` only evaluates the pose-dependent part.

    Parameters
    ----------
    room : Room
    layout : ReflectorLayout
    wavelength_m : float
    link_w_m2 : float
        ``P_T G_T G_R lambda^2`` in W m^2.
    max_order : int
        Largest number of surface bounces ``K``.
    body_shadowing : bool
        Drop the paths the robot's body blocks (see the module docstring).
    antenna : ZenithPattern, optional
        Elevation pattern; ``None`` is omnidirectional.
    min_power_w : float
        Reflector paths at or below this power are dropped early (they cannot show).
    """

    def __init__(
        self,
        room: Room,
        layout: ReflectorLayout,
        wavelength_m: float,
        link_w_m2: float,
        max_order: int = 2,
        *,
        body_shadowing: bool = False,
        antenna: ZenithPattern | None = None,
        min_power_w: float = 0.0,
    ) -> None:
        if room.surfaces is None:
            raise ValueError(
                "room.surfaces: the channel needs the surfaces' reflection coefficients"
            )
        self.surfaces = room.surfaces
        self.room = room
        self.body_shadowing = bool(body_shadowing)
        self.antenna = antenna
        self.layout = layout
        self.wavelength_m = float(wavelength_m)
        self.link_w_m2 = float(link_w_m2)
        self.max_order = int(max_order)
        size = room.size_m
        idx = np.vstack([np.zeros((1, 3), int), lattice_indices(self.max_order)])
        self.indices = idx  # row 0 is the radar itself
        self.image_order = np.abs(idx).sum(axis=1)
        self.image_gamma = lattice_gamma(idx, self.surfaces.face_coefficients())
        self.mirror = np.where(idx % 2 != 0, -1.0, 1.0)  # velocity mirroring per axis
        self.mirror[:, 2] = 0.0  # the radar moves in the floor plane
        # Reflector path pairs (a <= b): the reciprocal pair is folded in with amplitude 2.
        a, b = np.triu_indices(len(idx))
        keep = self.image_order[a] + self.image_order[b] <= self.max_order
        self.pair_a, self.pair_b = a[keep], b[keep]
        self.pair_amp2 = np.where(self.pair_a == self.pair_b, 1.0, 4.0)
        self.pair_order = self.image_order[self.pair_a] + self.image_order[self.pair_b]
        self.pair_gamma2 = (self.image_gamma[self.pair_a] * self.image_gamma[self.pair_b]) ** 2
        types = [layout.types[i] for i in layout.type_index]
        self._retro = np.array([t.half_angle_deg is not None for t in types], dtype=bool)
        self._any_retro = bool(self._retro.any())
        # per reflector: sqrt(peak RCS), log-amplitude lobe coefficient per deg^2, cutoff
        self._amp_peak = np.sqrt(layout.rcs_m2) if len(layout) else np.zeros(0)
        half = np.array([t.half_angle_deg or np.inf for t in types], dtype=float)
        self._lobe_coef = -0.5 * 0.3 * np.log(10.0) / half**2
        self._cos_cutoff = np.cos(np.radians([min(t.cutoff_deg, 180.0) for t in types]))
        self._pair_scale = ((self.link_w_m2 / FOUR_PI**3) * self.pair_amp2 * self.pair_gamma2)[
            :, None
        ]
        self._min_power_w = float(min_power_w)
        self._planes = _crossing_planes(idx, size, self.max_order)
        self._faces = self._obstacle_faces()
        # The leg next to the radar of the path that ends at image n leaves the radar towards
        # the image of the far end under the lattice inverse: same index where odd, negated
        # where even (the odd maps are involutions, the even ones translations).
        self.inverse_indices = np.where(idx % 2 != 0, idx, -idx)
        nz = idx[:, 2]
        single_axis = np.count_nonzero(idx, axis=1) == 1
        retraces = single_axis & (self.image_order % 2 == 0) & (self.image_order > 0)
        # surface path n leaves towards image n and comes back from image inverse(n)
        below = (nz < 0) | (self.inverse_indices[:, 2] < 0)
        self.surface_blocked_by_body = retraces | below

    # ------------------------------------------------------------------ geometry helpers
    def _obstacle_faces(self) -> dict[str, np.ndarray]:
        """Faces of the obstacles not lying on a room face: axis, coordinate, sign, bounds."""
        rows = []
        size = self.room.size_m
        for box in self.room.obstacles:
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

    def _inverse_image_z(self, z: np.ndarray) -> np.ndarray:
        """Heights (I, M) of the points ``z`` (M,) mirrored by the inverse lattice maps."""
        n = self.inverse_indices[:, 2:3]
        h = self.room.size_m[2]
        return np.where(n % 2 != 0, (n + 1) * h - z[None, :], n * h + z[None, :])

    @cached_property
    def has_obstacles(self) -> bool:
        return len(self.room.obstacles) > 0

    def _visible(self, start: np.ndarray, images: np.ndarray, img_index: np.ndarray) -> np.ndarray:
        """Whether the folded path from ``start`` (..., 3) to image ``images`` (..., 3) is clear.

        ``img_index`` (...) is the lattice row of each image; the path is unfolded from the
        point in the real room to its image, its plane crossings folded back into the room
        give the bounce points.
        """
        if not self.has_obstacles:
            return np.ones(images.shape[:-1], bool)
        axis, coord, valid = (p[img_index] for p in self._planes)  # (..., K)
        s = np.broadcast_to(start, images.shape)
        d = images - s
        ps = np.take_along_axis(s, axis, axis=-1)
        pd = np.take_along_axis(d, axis, axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(valid, (coord - ps) / pd, 1.0)
        t = np.sort(np.nan_to_num(t, nan=1.0), axis=-1)
        pts = s[..., None, :] + t[..., None] * d[..., None, :]
        poly = np.concatenate(
            [
                s[..., None, :],
                _fold(pts, self.room.size_m),
                _fold(images, self.room.size_m)[..., None, :],
            ],
            axis=-2,
        )
        blocked = self.room.segments_blocked(poly[..., :-1, :], poly[..., 1:, :])
        return ~np.any(blocked, axis=-1)

    # ------------------------------------------------------------------ the paths
    def paths(
        self,
        radar_pos_m: np.ndarray,
        velocity_xy_mps: np.ndarray,
        *,
        hidden: np.ndarray | None = None,
        extra_scatterers: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> Paths:
        """All propagation paths for a radar at ``radar_pos_m`` (3,) moving at ``velocity_xy_mps``.

        Parameters
        ----------
        radar_pos_m : array (3,)
        velocity_xy_mps : array (2,)
            Radar velocity in the floor plane.
        hidden : bool array (M,), optional
            Reflectors to leave out this frame.
        extra_scatterers : (positions (K, 3), rcs_m2 (K,)), optional
            Point clutter, direct paths only.
        """
        r = np.asarray(radar_pos_m, float)
        v = np.array([velocity_xy_mps[0], velocity_xy_mps[1], 0.0], float)
        lam = self.wavelength_m
        imgs = image_positions(r, self.indices, self.room.size_m)  # (I, 3)
        img_vel = self.mirror * v  # (I, 3)
        parts = [self._surface_paths(r, v, imgs, img_vel)]
        if self._faces["axis"].size:
            parts.append(self._face_paths(r, v))
        if len(self.layout):
            parts.append(self._reflector_paths(r, imgs, img_vel, hidden))
        if extra_scatterers is not None and len(extra_scatterers[0]):
            parts.append(self._scatterer_paths(r, v, *extra_scatterers))
        out = Paths.concatenate(parts)
        phase = FOUR_PI * out.range_m / lam + np.pi * out.order
        return Paths(
            out.range_m,
            out.velocity_mps,
            out.power_w,
            phase,
            out.reflector_index,
            out.order,
            out.kind,
        )

    def _surface_paths(self, r, v, imgs, img_vel) -> Paths:
        sel = slice(1, None)
        d = r - imgs[sel]
        length = np.linalg.norm(d, axis=1)
        rate = np.einsum("ik,ik->i", d, v - img_vel[sel]) / length
        power = self.link_w_m2 * self.image_gamma[sel] ** 2 / ((FOUR_PI * length) ** 2)
        order = self.image_order[sel]
        if self.antenna is not None:
            dz_out = imgs[sel, 2] - r[2]
            dz_back = image_positions(r, self.inverse_indices[sel], self.room.size_m)[:, 2] - r[2]
            power = power * self.antenna.gain(dz_out / length) * self.antenna.gain(dz_back / length)
        ok = ~self.surface_blocked_by_body[sel] if self.body_shadowing else None
        if self.has_obstacles:
            vis = self._visible(r, imgs[sel], np.arange(1, len(imgs)))
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

    def _face_paths(self, r, v) -> Paths:
        f = self._faces
        ax = f["axis"]
        dist = f["sign"] * (r[ax] - f["coord"])
        foot = np.broadcast_to(r, (len(ax), 3)).copy()
        foot[np.arange(len(ax)), ax] = f["coord"]
        on_face = np.all((foot >= f["lo"] - 1e-12) & (foot <= f["hi"] + 1e-12), axis=1)
        ok = (dist > 0) & on_face
        ok &= ~self.room.segments_blocked(np.broadcast_to(r, foot.shape), foot)
        if self.body_shadowing:
            ok &= foot[:, 2] >= r[2] - 1e-9  # a face seen from above lies below the deck
        dist, rate, dz = dist[ok], (f["sign"] * v[ax])[ok], foot[ok, 2] - r[2]
        g = self.surfaces.obstacles
        power = self.link_w_m2 * g**2 / (FOUR_PI * 2.0 * dist) ** 2
        if self.antenna is not None:
            power = power * self.antenna.gain(dz / dist) ** 2
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

    def _reflector_paths(self, r, imgs, img_vel, hidden) -> Paths:
        lay = self.layout
        pos = lay.positions_m  # (M, 3)
        d = imgs[:, None, :] - pos[None, :, :]  # (I, M, 3) from reflector towards image
        dist = np.sqrt(np.einsum("imk,imk->im", d, d))
        u = d / dist[..., None]
        rate = np.einsum("imk,ik->im", u, img_vel)  # one-way length rate
        amp = self._rcs_amplitude(np.einsum("imk,mk->im", u, lay.axes))  # sqrt(sigma), (I, M)
        a, b = self.pair_a, self.pair_b
        sig = amp[a] * amp[b]
        if self._any_retro:
            cos_beta = np.einsum("pmk,pmk->pm", u[a], u[b])
            beta = np.degrees(np.arccos(np.clip(cos_beta, -1.0, 1.0)))
            lobe = np.exp((-0.3 * np.log(10.0) / RETRO_LOBE_DEG**2) * beta**2)
            sig = np.where(self._retro, sig * lobe, sig)
        power = self._pair_scale * sig / (dist[a] * dist[b]) ** 2
        if self.antenna is not None or self.body_shadowing:
            # height of the far end of each leg's radar-side segment, relative to the radar
            dz = self._inverse_image_z(pos[:, 2]) - r[2]  # (I, M)
            if self.antenna is not None:
                g = self.antenna.gain(dz / dist)
                power = power * (g[a] * g[b])
            if self.body_shadowing:
                up = dz >= -1e-9
                power = np.where(up[a] & up[b], power, 0.0)
        if hidden is not None:
            power = np.where(np.asarray(hidden, bool)[None, :], 0.0, power)
        keep = power > self._min_power_w
        if self.has_obstacles:
            vis = self._visible(
                pos[None, :, :],
                np.broadcast_to(imgs[:, None, :], d.shape),
                np.broadcast_to(np.arange(len(imgs))[:, None], dist.shape),
            )
            keep &= vis[a] & vis[b]
        pi, mi = np.nonzero(keep)
        ai, bi = a[pi], b[pi]
        order = self.pair_order[pi]
        return Paths(
            0.5 * (dist[ai, mi] + dist[bi, mi]),
            0.5 * (rate[ai, mi] + rate[bi, mi]),
            power[pi, mi],
            np.zeros(len(pi)),
            mi,
            order,
            np.where(order == 0, KIND_DIRECT, KIND_REFLECTOR_MULTIPATH),
        )

    def _rcs_amplitude(self, cos_incidence: np.ndarray) -> np.ndarray:
        """``sqrt`` of the RCS each reflector shows at the incidence cosines (..., M).

        The same Gaussian lobe and cutoff as :meth:`ReflectorType.pattern`, vectorised over
        the reflectors.
        """
        c = np.clip(cos_incidence, -1.0, 1.0)
        angle2 = np.degrees(np.arccos(c)) ** 2
        amp = self._amp_peak * np.exp(self._lobe_coef * angle2)
        return np.where(c >= self._cos_cutoff, amp, 0.0)

    def _scatterer_paths(self, r, v, positions, rcs_m2) -> Paths:
        pos = np.asarray(positions, float).reshape(-1, 3)
        rcs = np.asarray(rcs_m2, float).reshape(-1)
        d = r - pos
        dist = np.linalg.norm(d, axis=1)
        rate = d @ v / dist
        power = self.link_w_m2 * rcs / (FOUR_PI**3 * dist**4)
        ok = ~self.room.segments_blocked(np.broadcast_to(r, pos.shape), pos) & (dist > 0)
        if self.body_shadowing:
            ok &= pos[:, 2] >= r[2] - 1e-9
        if self.antenna is not None:
            power = power * self.antenna.gain((pos[:, 2] - r[2]) / np.maximum(dist, 1e-12)) ** 2
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
