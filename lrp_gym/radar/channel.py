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

This module enumerates the paths and computes the reflectors' returns; the pose-free lattice
geometry is in :mod:`lrp_gym.radar.image_lattice`, the returns of the room's structure (its
faces, obstacle faces, point scatterers) in :mod:`lrp_gym.radar.structure_returns`, and the
:class:`~lrp_gym.radar.paths.Paths` record in :mod:`lrp_gym.radar.paths`.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from lrp_gym.radar.antenna import ZenithPattern
from lrp_gym.radar.image_lattice import (
    crossing_planes,
    fold,
    image_positions,
    lattice_gamma,
    lattice_indices,
)
from lrp_gym.radar.paths import (
    KIND_DIRECT,
    KIND_REFLECTOR_MULTIPATH,
    Paths,
)
from lrp_gym.radar.structure_returns import (
    obstacle_face_paths,
    obstacle_faces,
    scatterer_paths,
    surface_paths,
)
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.room import Room

FOUR_PI = 4.0 * np.pi

#: -3 dB bistatic half angle of a retro-directive reflector's return lobe.
RETRO_LOBE_DEG = 5.0


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
        idx = np.vstack([np.zeros((1, 3), int), lattice_indices(self.max_order)])
        self.indices = idx  # row 0 is the radar itself
        self.image_order = np.abs(idx).sum(axis=1)
        self.image_gamma = lattice_gamma(idx, self.surfaces.face_coefficients())
        self.mirror = np.where(idx % 2 != 0, -1.0, 1.0)  # velocity mirroring per axis
        self.mirror[:, 2] = 0.0  # the radar moves in the floor plane
        self._init_pairs()
        self._init_reflector_patterns(layout)
        self._pair_scale = ((self.link_w_m2 / FOUR_PI**3) * self.pair_amp2 * self.pair_gamma2)[
            :, None
        ]
        self._min_power_w = float(min_power_w)
        self._planes = crossing_planes(idx, room.size_m, self.max_order)
        self.faces = obstacle_faces(room)
        self._init_body_blocking()

    def _init_pairs(self) -> None:
        """Reflector path pairs (a <= b) of order <= K: the reciprocal pair is folded in with
        amplitude 2 (power 4)."""
        a, b = np.triu_indices(len(self.indices))
        keep = self.image_order[a] + self.image_order[b] <= self.max_order
        self.pair_a, self.pair_b = a[keep], b[keep]
        self.pair_amp2 = np.where(self.pair_a == self.pair_b, 1.0, 4.0)
        self.pair_order = self.image_order[self.pair_a] + self.image_order[self.pair_b]
        self.pair_gamma2 = (self.image_gamma[self.pair_a] * self.image_gamma[self.pair_b]) ** 2

    def _init_reflector_patterns(self, layout: ReflectorLayout) -> None:
        """Per reflector: retro-directive or not, sqrt(peak RCS), log-amplitude lobe
        coefficient per deg^2 and the cosine of the cutoff angle."""
        types = [layout.types[i] for i in layout.type_index]
        self._retro = np.array([t.half_angle_deg is not None for t in types], dtype=bool)
        self._any_retro = bool(self._retro.any())
        self._amp_peak = np.sqrt(layout.rcs_m2) if len(layout) else np.zeros(0)
        half = np.array([t.half_angle_deg or np.inf for t in types], dtype=float)
        self._lobe_coef = -0.5 * 0.3 * np.log(10.0) / half**2
        self._cos_cutoff = np.cos(np.radians([min(t.cutoff_deg, 180.0) for t in types]))

    def _init_body_blocking(self) -> None:
        """The lattice inverse of each image and which surface paths the robot's body blocks."""
        idx = self.indices
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
    def _inverse_image_z(self, z: np.ndarray) -> np.ndarray:
        """Heights (I, M) of the points ``z`` (M,) mirrored by the inverse lattice maps."""
        n = self.inverse_indices[:, 2:3]
        h = self.room.size_m[2]
        return np.where(n % 2 != 0, (n + 1) * h - z[None, :], n * h + z[None, :])

    @cached_property
    def has_obstacles(self) -> bool:
        return len(self.room.obstacles) > 0

    def visible(self, start: np.ndarray, images: np.ndarray, img_index: np.ndarray) -> np.ndarray:
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
                fold(pts, self.room.size_m),
                fold(images, self.room.size_m)[..., None, :],
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
        parts = [surface_paths(self, r, v, imgs, img_vel)]
        if self.faces["axis"].size:
            parts.append(obstacle_face_paths(self, r, v))
        if len(self.layout):
            parts.append(self._reflector_paths(r, imgs, img_vel, hidden))
        if extra_scatterers is not None and len(extra_scatterers[0]):
            parts.append(scatterer_paths(self, r, v, *extra_scatterers))
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
            vis = self.visible(
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
