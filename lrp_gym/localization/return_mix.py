"""What the reflector-like returns of a room are made of: direct, via the room's faces, or the
room itself.

Besides clutter, the localiser's likelihood explains a measured distance that passes the
tracker's RCS window in three ways: a reflector's direct return, a reflector seen via a face
of the room (its ghost, an image path), or a return of the room's structure (ceiling, edges,
walls). How often each happens depends on the room and on the reflectors: in the paper's room
of trihedrals about a third are direct, a twentieth ghosts and the rest the room, but in a
room of spheres or Luneburg lenses, which scatter in every direction and so see the radar in
every face, about two thirds are ghosts. :func:`return_mix` measures the shares at random free
poses: each detection whose RCS lies in some type's window is attributed to the strongest
propagation path within one range bin of it, whose kind the channel knows. The RCS and range
windows are the tracker's (:class:`~lrp_gym.tracking.classify.LrpClassifier`): the returns
measured are those the localiser weighs.

The ghosts are far from alike: a sphere's ghost via one face is much stronger than one via two,
and one near a wall much stronger than one across the room. Of the 170 ghost rows that
:class:`~lrp_gym.localization.ghosts.GhostModel` predicts for five spheres, a survey of 200
frames finds six holding half of the ghost returns and 122 never. :func:`return_mix` therefore
also counts the returns of each predicted ghost (the row whose range at the survey pose is
nearest the path's, same reflector), and :meth:`ReturnMix.ghost_row_weights` turns the counts
into the likelihood's weights of the rows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lrp_gym.config import ScenarioConfig
from lrp_gym.localization.ghosts import GhostModel
from lrp_gym.radar.delivery_rate import random_poses
from lrp_gym.radar.paths import KIND_DIRECT, KIND_REFLECTOR_MULTIPATH, KIND_SURFACE
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.tracking.tracker import LrpTracker
from lrp_gym.world.world import World


@dataclass(frozen=True)
class ReturnMix:
    """Shares of the RCS-window returns by origin (they sum to 1 when ``n_returns`` > 0).

    Attributes
    ----------
    direct, ghost, structure : float
        A reflector's direct return; a reflector via one or two faces of the room; the room's
        surfaces.
    other : float
        Anything else (obstacle faces, extra scatterers, no path within a range bin).
    n_returns, n_poses : int
        Returns attributed, and the poses they came from.
    ghost_row_counts : tuple of int (G,)
        Ghost returns attributed to each row of the layout's
        :class:`~lrp_gym.localization.ghosts.GhostModel`.
    ghost_row_bounces : tuple of int (G,)
        Face bounces of each row (1 or 2; :attr:`GhostModel.row_bounces`).
    ghost_row_classes : tuple of int (G,)
        Rows alike but for geometry share a class: the same reflector type, bounces and
        pair kind (same face both ways, direct one way, any pair of an omnidirectional type).
    ghost_row_reflector : tuple of int (G,)
        Layout index of each row's reflector (:attr:`GhostModel.row_reflector`).
    """

    direct: float
    ghost: float
    structure: float
    other: float
    n_returns: int
    n_poses: int
    ghost_row_counts: tuple[int, ...] = ()
    ghost_row_bounces: tuple[int, ...] = ()
    ghost_row_classes: tuple[int, ...] = ()
    ghost_row_reflector: tuple[int, ...] = ()

    def ghost_row_weights(self) -> np.ndarray:
        """Relative weight (G,) of each ghost row, summing to 1: the posterior mean of the
        row's rate of returns per survey, its count shrunk towards its class's mean ``m``
        (a gamma prior of shape 1 and mean ``m``: ``(count + 1) / (1 + 1 / m)``, with ``m``
        counting one return more than the class had, so that none is 0). A row never seen
        in a class seen often is thus weighed as about one return, not as its class's mean."""
        counts = np.asarray(self.ghost_row_counts, dtype=float)
        classes = np.asarray(self.ghost_row_classes, dtype=int)
        weights = np.zeros_like(counts)
        for c in np.unique(classes):
            rows = classes == c
            mean = (counts[rows].sum() + 1.0) / rows.sum()
            weights[rows] = (counts[rows] + 1.0) / (1.0 + 1.0 / mean)
        return weights / weights.sum() if weights.sum() > 0 else weights

    def map_return_probabilities(self, floor: float = 0.01) -> tuple[float, float]:
        """``(structure_probability, ghost_probability)`` of the likelihood: the shares of
        the structure and the ghosts among the returns the map explains (direct, ghost,
        structure), each at least ``floor`` (a survey of a few hundred frames cannot prove a
        kind absent). ``(floor, floor)`` scaled to nothing measured keeps both classes."""
        mapped = self.direct + self.ghost + self.structure
        if not mapped > 0.0:
            return floor, floor
        return max(self.structure / mapped, floor), max(self.ghost / mapped, floor)


def return_mix(cfg: ScenarioConfig, n_poses: int = 200, seed: int = 0) -> ReturnMix:
    """The :class:`ReturnMix` of scenario ``cfg``'s radar at ``n_poses`` random free poses.

    Parameters
    ----------
    cfg : ScenarioConfig
        Its room, reflectors, radar (at its fidelity) and the tracker's RCS windows.
    n_poses : int
        Radar frames to attribute (at least 1).
    seed : int
        Seeds the poses and the radar noise.
    """
    if n_poses < 1:
        raise ValueError(f"n_poses: must be at least 1, got {n_poses}")
    world = World.from_config(cfg)
    sensor = RadarSensor(world, cfg.radar)
    rng = np.random.default_rng(seed)
    poses, vels = random_poses(world, n_poses, rng, cfg.robot.radius_m, cfg.robot.max_speed_mps)
    classifier = LrpTracker.from_world(world, cfg.tracking).classifier
    ghosts = GhostModel(world.room, world.layout, world.mount_height_m)
    bin_m = world.fmcw.range_resolution_m
    counts = np.zeros(4)  # direct, ghost, structure, other
    row_counts = np.zeros(ghosts.count, dtype=int)
    for pose, vel in zip(poses, vels, strict=True):
        paths = sensor.paths(pose, vel)
        det = sensor.detect(paths, rng)
        ghost_m = ghosts.ranges(pose[None, :2])[0][:, 0]
        for r in det.range_m[classifier.candidates(det).any(axis=1)]:
            near = np.flatnonzero(np.abs(paths.range_m - r) <= bin_m)
            path = near[np.argmax(paths.power_w[near])] if len(near) else -1
            kind = paths.kind[path] if len(near) else -1
            counts[_SLOT.get(int(kind), 3)] += 1
            if kind == KIND_REFLECTOR_MULTIPATH:
                rows = np.flatnonzero(ghosts.row_reflector == paths.reflector_index[path])
                diff = np.abs(ghost_m[rows] - paths.range_m[path])
                if diff.min() <= bin_m:  # the row that predicts this path
                    row_counts[rows[np.argmin(diff)]] += 1
    n = int(counts.sum())
    share = counts / n if n else np.zeros(4)
    return ReturnMix(
        *(float(s) for s in share),
        n_returns=n,
        n_poses=int(n_poses),
        ghost_row_counts=tuple(int(c) for c in row_counts),
        ghost_row_bounces=tuple(int(b) for b in ghosts.row_bounces),
        ghost_row_reflector=tuple(int(m) for m in ghosts.row_reflector),
        ghost_row_classes=tuple(int(c) for c in _row_classes(world, ghosts)),
    )


def _row_classes(world: World, ghosts: GhostModel) -> np.ndarray:
    """Class index (G,) of each ghost row: its reflector's type, bounces and pair kind."""
    kind = np.c_[world.layout.type_index[ghosts.row_reflector], ghosts.row_bounces]
    kind = np.c_[kind, ghosts.row_bistatic]
    return np.unique(kind, axis=0, return_inverse=True)[1].reshape(-1)


#: Slot of a path kind in :func:`return_mix`'s counts (others: 3).
_SLOT = {KIND_DIRECT: 0, KIND_REFLECTOR_MULTIPATH: 1, KIND_SURFACE: 2}
