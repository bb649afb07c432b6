"""How likely the radar is to detect each mapped reflector from a floor position.

A reflector returns nothing to a radar that an obstacle hides it from, that stands past the
cutoff of its pattern, or that is out of the radar's range; and a reflector seen at a low
pattern or antenna gain, or far away, often drowns in the noise. The radar simulation works
all of this out per path (:class:`lrp_gym.radar.channel.Channel`,
:mod:`lrp_gym.radar.detection_model`). A likelihood that expects every reflector everywhere
with one detection probability holds a hidden reflector's silence against the true pose
(negative information) and lets a pose that cannot see a reflector explain a measured
distance with it.

:class:`ReflectorVisibility` gives the likelihood the same geometry and, with a
:class:`RadarLink` (the radar's link budget and CFAR threshold), each reflector's
probability of detection from its SNR: the radar equation for the direct path, the
window's scalloping loss and a Rician peak in Gaussian noise against the CFAR threshold.
The likelihood multiplies it with its ``detection_probability`` (which covers what the
radar equation does not: masking by stronger returns, merged peaks, the tracker).

:meth:`ReflectorVisibility.for_world` returns None when every reflector is detected with
probability >= 0.99 from everywhere on the floor (the paper room): such rooms keep the plain
model, bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
from scipy.stats import ncx2

from lrp_gym.radar.detection_model import cfar_threshold_w
from lrp_gym.world.reflector_view import reflector_view
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.room import Room

if TYPE_CHECKING:
    from lrp_gym.radar.antenna import ZenithPattern
    from lrp_gym.radar.sensor import RadarSensor
    from lrp_gym.world.world import World

#: The expected range the likelihood gives a reflector the position cannot see (m): far past
#: any radar's range, so its kernel against every measured distance is exactly 0 in float32.
HIDDEN_RANGE_M = 1.0e4
#: A reflector detected with a lower probability than this counts as not visible: it
#: explains no measured distance.
MIN_DETECTION_PROBABILITY = 0.01
#: ... and one detected with at least this probability everywhere needs no model.
SURE_DETECTION_PROBABILITY = 0.99
#: Largest cell of a :class:`VisibilityMap` (m).
MAP_CELL_M = 0.025
#: Spacing of the floor grid on which :meth:`ReflectorVisibility.for_world` decides whether
#: the room needs the model at all (m).
_SURVEY_GRID_M = 0.05
#: SNR axis (dB) of the detection-probability table; sub-bin offsets per axis averaged.
_SNR_DB = np.arange(-30.0, 80.0, 0.25)
_OFFSETS = np.linspace(-0.5, 0.5, 11)
FOUR_PI = 4.0 * np.pi


@dataclass(frozen=True)
class RadarLink:
    """What the localiser knows of its radar: enough to predict a reflector's detection.

    Attributes
    ----------
    link_w_m2 : float
        Transmit power times both antenna gains times ``lambda^2`` (W m^2): a point target
        of RCS ``s`` at range ``d`` returns ``link_w_m2 s / ((4 pi)^3 d^4)`` watts.
    antenna : ZenithPattern or None
        The antenna's power pattern over the zenith angle, applied on the way out and back
        (None: isotropic).
    body_shadowing : bool
        The robot's deck hides returns from below the radar.
    snr_per_w : float
        Clean map peak over one cell's noise, per watt at the antenna port (no scalloping).
    min_range_m : float
        Detections nearer than this are dropped.
    pd_table : ndarray
        Detection probability on the SNR axis ``_SNR_DB`` (scalloping and noise averaged).
    delivery : ndarray (M,) or None
        Per reflector, the factor a calibration survey found between how often the radar
        delivers it in view and what the likelihood's ``detection_probability`` assumes
        (:meth:`surveyed`); None: 1 for all.
    ghost_weights : ndarray (G,) or None
        Relative weight of each of the layout's predicted ghosts (the rows of
        :class:`~lrp_gym.localization.ghosts.GhostModel`), from how often a survey found
        each among the radar's returns (:meth:`with_ghost_weights`); None: all alike.
    ghost_reflector : ndarray of int (G,) or None
        The reflector of each weighted ghost (to reduce the layout with).
    """

    link_w_m2: float
    antenna: ZenithPattern | None
    body_shadowing: bool
    snr_per_w: float
    min_range_m: float
    pd_table: np.ndarray
    delivery: np.ndarray | None = None
    ghost_weights: np.ndarray | None = None
    ghost_reflector: np.ndarray | None = None

    @classmethod
    def from_sensor(cls, sensor: RadarSensor) -> RadarLink:
        """The link of ``sensor`` (its configuration as surveyed)."""
        proc = sensor.processor
        cell = sensor.noise_cell
        threshold = cfar_threshold_w(sensor) / cell  # in units of one cell's noise
        g_r = np.interp(_OFFSETS, proc.range_table.offset, proc.range_table.gain)
        g_d = np.interp(_OFFSETS, proc.doppler_table.offset, proc.doppler_table.gain)
        loss = (g_r[:, None] * g_d[None, :]).ravel() ** 2  # scalloping power loss
        snr = 10.0 ** (_SNR_DB / 10.0)[:, None] * loss[None, :]
        if sensor.noise_on:
            # |sqrt(S) + n|^2 with complex Gaussian noise of unit power: 2x it is a
            # non-central chi-square with 2 degrees of freedom and non-centrality 2 S.
            pd = ncx2.sf(2.0 * threshold, 2, 2.0 * snr).mean(axis=1)
        else:
            pd = (snr > threshold).mean(axis=1)
        return cls(
            link_w_m2=float(sensor.link_w_m2),
            antenna=sensor.channel.antenna,
            body_shadowing=bool(sensor.channel.body_shadowing),
            snr_per_w=float(proc.coherent_gain2 / cell),
            min_range_m=float(sensor.min_range_m),
            pd_table=pd,
        )

    def surveyed(self, in_view_rates: np.ndarray, detection_probability: float) -> RadarLink:
        """This link with each reflector's detection scaled down so that
        ``detection_probability`` times it is the reflector's delivered rate in view
        (``in_view_rates`` (M,), NaN for one never in view: unscaled), at least 0.05 (a survey
        of a few hundred frames cannot prove a reflector silent). Never up: a reflector's
        misses repeat along the path, so a per-frame rate above ``detection_probability``
        would charge the true pose for one lasting miss again and again (docs/trust.md)."""
        rates = np.asarray(in_view_rates, dtype=float)
        target = np.where(np.isnan(rates), detection_probability, rates)
        target = np.clip(np.minimum(target, detection_probability), 0.05, None)
        return replace(self, delivery=target / detection_probability)

    def with_ghost_weights(self, weights: np.ndarray, reflector: np.ndarray) -> RadarLink:
        """This link with the ghost rows weighted by ``weights`` (G,), the rows of the
        reflectors ``reflector`` (G,) (layout indices)."""
        weights, reflector = np.asarray(weights, dtype=float), np.asarray(reflector)
        if weights.shape != reflector.shape or np.any(weights < 0):
            raise ValueError("ghost weights: one non-negative weight per ghost row expected")
        return replace(self, ghost_weights=weights, ghost_reflector=reflector)

    def of_reflectors(self, keep: np.ndarray) -> RadarLink:
        """This link for the layout reduced to the reflectors ``keep`` (indices, layout
        order): their survey's scaling and their ghosts' weights kept, the others' dropped.
        The kept ghost rows stay in order, which is the order of the reduced layout's rows."""
        link = self if self.delivery is None else replace(self, delivery=self.delivery[keep])
        if self.ghost_weights is None:
            return link
        rows = np.isin(self.ghost_reflector, keep)
        new_index = np.searchsorted(np.asarray(keep), self.ghost_reflector[rows])
        return replace(link, ghost_weights=self.ghost_weights[rows], ghost_reflector=new_index)

    def detection_probability(
        self, rcs_m2: np.ndarray, dist_m: np.ndarray, cos_zenith: np.ndarray
    ) -> np.ndarray:
        """Probability that a reflector showing ``rcs_m2`` at range ``dist_m`` in the
        direction of zenith cosine ``cos_zenith`` (radar to reflector) is detected."""
        power = self.link_w_m2 * rcs_m2 / (FOUR_PI**3 * np.maximum(dist_m, 1e-6) ** 4)
        if self.antenna is not None:
            power = power * self.antenna.gain(cos_zenith) ** 2
        with np.errstate(divide="ignore"):
            snr_db = 10.0 * np.log10(power * self.snr_per_w)
        pd = np.interp(snr_db, _SNR_DB, self.pd_table, left=0.0)
        pd = np.where(dist_m >= self.min_range_m, pd, 0.0)
        if self.body_shadowing:
            pd = np.where(cos_zenith >= -1e-9, pd, 0.0)
        return pd


class ReflectorVisibility:
    """Line of sight, pattern, range and (with a ``link``) SNR of each reflector.

    Parameters
    ----------
    room : Room
        Its obstacles (axis-aligned boxes) block lines of sight.
    layout : ReflectorLayout
        Reflector positions, boresights, patterns and RCS.
    mount_height_m : float
        Height of the radar above the floor.
    max_range_m : float
        The radar's largest measurable range.
    link : RadarLink, optional
        The radar's link budget; None: a reflector in view is detected (probability 1).
    """

    def __init__(
        self,
        room: Room,
        layout: ReflectorLayout,
        mount_height_m: float,
        max_range_m: float,
        link: RadarLink | None = None,
    ) -> None:
        self.room = room
        self.layout = layout
        self.mount_height_m = float(mount_height_m)
        self.max_range_m = float(max_range_m)
        self.link = link

    @classmethod
    def of(cls, world: World, link: RadarLink | None = None) -> ReflectorVisibility:
        """The model of ``world``'s room, layout, radar height and range (exact)."""
        return cls(world.room, world.layout, world.mount_height_m, world.fmcw.max_range_m, link)

    @classmethod
    def for_world(cls, world: World, link: RadarLink | None = None) -> VisibilityMap | None:
        """The model of ``world`` as a :class:`VisibilityMap`, or None when it is not
        :meth:`needed`."""
        vis = cls.of(world, link)
        return VisibilityMap(vis, world.room.size_m[:2]) if vis.needed() else None

    def needed(self) -> bool:
        """Whether some reflector is detected with probability below
        :data:`SURE_DETECTION_PROBABILITY` from some free point of a 5 cm floor grid of the
        room (else there is nothing to model)."""
        size = self.room.size_m
        axes = [np.arange(_SURVEY_GRID_M / 2, size[k], _SURVEY_GRID_M) for k in range(2)]
        xy = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 2)
        xy = xy[self.room.free(xy)]
        return len(xy) > 0 and self.detection_probability(xy).min() < SURE_DETECTION_PROBABILITY

    def detection_probability(self, xy: np.ndarray) -> np.ndarray:
        """Probability (M, N) that reflector ``j`` is detected by a radar at floor position
        ``xy[i]`` (N, 2), in layout order: 0 where it is out of view."""
        view = reflector_view(self.room, self.layout, self.mount_height_m, self.max_range_m, xy)
        if self.link is None:
            return view.in_view.astype(float)
        rcs = view.gain * self.layout.rcs_m2[:, None]
        pd = self.link.detection_probability(rcs, view.dist_m, view.cos_zenith)
        if self.link.delivery is not None:
            pd = pd * self.link.delivery[:, None]
        return np.where(view.in_view, pd, 0.0)

    def visible(self, xy: np.ndarray) -> np.ndarray:
        """Boolean (M, N): the reflectors a radar at floor positions ``xy`` (N, 2) can see
        (detection probability at least :data:`MIN_DETECTION_PROBABILITY`)."""
        return self.detection_probability(xy) >= MIN_DETECTION_PROBABILITY


class VisibilityMap:
    """:meth:`ReflectorVisibility.detection_probability` tabulated on a floor grid and
    interpolated bilinearly: the per-frame cost for thousands of particles is a gather.

    The grid's cells are at most :data:`MAP_CELL_M` wide (coarser in large rooms, to hold at
    most ``max_cells`` nodes). A shadow's edge is soft over about a Fresnel zone,
    ``sqrt(lambda d)`` (7 cm at 60 GHz and 1 m behind the obstacle), wider than the cells.

    Parameters
    ----------
    visibility : ReflectorVisibility
        The exact model (:attr:`exact`).
    size_xy_m : array (2,)
        The room's floor extent.
    """

    def __init__(
        self, visibility: ReflectorVisibility, size_xy_m: np.ndarray, max_cells: int = 200_000
    ) -> None:
        self.exact = visibility
        self.link = visibility.link
        size = np.asarray(size_xy_m, dtype=float)
        cell = max(MAP_CELL_M, float(np.sqrt(np.prod(size) / max_cells)))
        self._n = np.maximum(np.ceil(size / cell).astype(int), 1) + 1  # nodes per axis
        self._cell = size / (self._n - 1)
        gx, gy = (np.arange(n) * c for n, c in zip(self._n, self._cell, strict=True))
        nodes = np.stack(np.meshgrid(gx, gy, indexing="ij"), axis=-1).reshape(-1, 2)
        #: (M, nodes) probabilities, node (i, j) at column ``i * ny + j``
        self.table = visibility.detection_probability(nodes).astype(np.float32)

    def detection_probability(self, xy: np.ndarray) -> np.ndarray:
        """Probability (M, N) of each reflector's detection from floor positions (N, 2)."""
        u = np.asarray(xy, dtype=float).reshape(-1, 2) / self._cell
        i0 = np.clip(np.floor(u).astype(np.intp), 0, self._n - 2)
        f = np.clip(u - i0, 0.0, 1.0).astype(np.float32)
        ny = self._n[1]
        k = i0[:, 0] * ny + i0[:, 1]
        t = self.table
        fx, fy = f[:, 0], f[:, 1]
        low = t[:, k] * (1.0 - fy) + t[:, k + 1] * fy
        high = t[:, k + ny] * (1.0 - fy) + t[:, k + ny + 1] * fy
        return low * (1.0 - fx) + high * fx

    def visible(self, xy: np.ndarray) -> np.ndarray:
        """Boolean (M, N), as :meth:`ReflectorVisibility.visible`."""
        return self.detection_probability(xy) >= MIN_DETECTION_PROBABILITY
