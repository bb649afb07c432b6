"""The non-reflector returns that the map predicts for a floor position: the room's structure
(ceiling, wall-ceiling edges, walls, corners; :mod:`lrp_gym.world.structure`) and the
reflectors' ghosts via the faces (:mod:`lrp_gym.localization.ghosts`), with their mixture
weights in the fingerprint likelihood.

A reflector-like return of the room counts as evidence for the positions that predict it
rather than as clutter that any position may borrow: each measured distance's reflector term
``mean_j N(z; e_j)`` is mixed with ``sum_k w_k N(z; g_k)`` over these predicted ranges ``g_k``,
the weights summing to the structure plus ghost probability.
"""

from __future__ import annotations

import numpy as np

from lrp_gym.localization._structure_kernel import structure_rows_jit
from lrp_gym.localization.ghosts import GhostModel
from lrp_gym.world.reflectors import ReflectorLayout
from lrp_gym.world.room import Room
from lrp_gym.world.structure import (
    N_STRUCTURE_RETURNS,
    structure_ranges_m,
    structure_velocities_mps,
)


class MapReturns:
    """Predicted structure and ghost returns of a room, and their mixture weights.

    Parameters
    ----------
    room : Room
        The room whose structure and faces produce the returns.
    layout : ReflectorLayout
        The reflectors whose ghosts are predicted.
    mount_height_m : float
        Radar height above the floor.
    structure_probability, ghost_probability : float
        Probability that a measured distance is a structure return, or a reflector's ghost;
        their sum is at most 1. A zero leaves that kind of return out.
    ghost_weights : ndarray (G,), optional
        Relative weight of each predicted ghost (the rows of
        :class:`~lrp_gym.localization.ghosts.GhostModel`), e.g. how often a survey found it
        (:func:`~lrp_gym.localization.return_mix.return_mix`); scaled to sum to
        ``ghost_probability``. None: all ghosts alike.
    """

    def __init__(
        self,
        room: Room,
        layout: ReflectorLayout,
        mount_height_m: float,
        structure_probability: float,
        ghost_probability: float,
        ghost_weights: np.ndarray | None = None,
    ) -> None:
        if structure_probability + ghost_probability > 1.0:
            raise ValueError(
                "structure_probability + ghost_probability must be <= 1, got "
                f"{structure_probability} + {ghost_probability}"
            )
        self.room = room
        self.mount_height_m = float(mount_height_m)
        self.structure_probability = float(structure_probability)
        self.ghost_probability = float(ghost_probability)
        self.ghosts = (
            GhostModel(room, layout, mount_height_m) if self.ghost_probability > 0.0 else None
        )
        parts = []
        if self.structure_probability > 0.0:
            w = self.structure_probability / N_STRUCTURE_RETURNS
            parts.append(np.full(N_STRUCTURE_RETURNS, w))
        if self.ghosts is not None:
            parts.append(_shares(self.ghost_probability, ghost_weights, self.ghosts.count))
        #: Mixture weight (K,) of each row of :meth:`ranges`; None when there is none.
        self.weights: np.ndarray | None = np.concatenate(parts) if parts else None
        #: Structure rows in float32 by the compiled kernel when numba is installed (the
        #: same bits as the numpy functions).
        self.use_numba = True

    @property
    def probability(self) -> float:
        """Total probability of the map's returns (the sum of :attr:`weights`)."""
        return self.structure_probability + self.ghost_probability

    def ranges(
        self, xy: np.ndarray, velocity_xy: np.ndarray | None, dtype=np.float32
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Ranges (K, N) of the predicted returns at positions (N, 2) (room structure, then
        reflector ghosts) and their radial velocities (K, N) given ``velocity_xy`` (N, 2), else
        None. Needs :attr:`weights` (at least one kind of return)."""
        ranges, rates = [], []
        if self.structure_probability > 0.0:
            r, v = self._structure(xy, velocity_xy, dtype)
            ranges.append(r)
            if v is not None:
                rates.append(v)
        if self.ghosts is not None:
            g, gv = self.ghosts.ranges(xy, velocity_xy, dtype)
            ranges.append(g)
            if gv is not None:
                rates.append(gv)
        r = np.concatenate(ranges) if len(ranges) > 1 else ranges[0]
        if velocity_xy is None:
            return r, None
        return r, (np.concatenate(rates) if len(rates) > 1 else rates[0])

    def _structure(
        self, xy: np.ndarray, velocity_xy: np.ndarray | None, dtype
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """The structure's rows (13, N) of :meth:`ranges` and, given velocities, their rates."""
        h = self.mount_height_m
        if np.dtype(dtype) != np.float32 or not self.use_numba or structure_rows_jit is None:
            r = structure_ranges_m(self.room, h, xy).astype(dtype)
            if velocity_xy is None:
                return r, None
            return r, structure_velocities_mps(self.room, h, xy, velocity_xy).astype(dtype)
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        n = xy.shape[0]
        out = np.empty((N_STRUCTURE_RETURNS, n), dtype=np.float32)
        v = np.zeros((0, 2))
        rates = out[:0]
        if velocity_xy is not None:
            v = np.atleast_2d(np.asarray(velocity_xy, dtype=float))
            rates = np.empty_like(out)
        lx, ly, lz = (float(s) for s in self.room.size_m)
        structure_rows_jit(xy, v, lx, ly, lz - h, out, rates)
        return out, (rates if velocity_xy is not None else None)


def _shares(total: float, weights: np.ndarray | None, count: int) -> np.ndarray:
    """``total`` shared among ``count`` rows in proportion to ``weights``; equally for None."""
    if weights is None:
        return np.full(count, total / count)
    weights = np.asarray(weights, dtype=float)
    if weights.shape != (count,) or np.any(weights < 0) or not weights.sum() > 0:
        raise ValueError(
            f"ghost_weights: {count} non-negative weights (one per ghost row) with a positive "
            f"sum expected, got shape {weights.shape}"
        )
    return total * (weights / weights.sum())  # the order the figures were measured with
