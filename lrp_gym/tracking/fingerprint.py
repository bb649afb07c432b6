"""The estimated LRP fingerprint: what positioning consumes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Fingerprint:
    """Unordered distances to the reflectors, per reflector type, in one frame.

    All per-type entries are tuples indexed like ``type_names``; each holds a 1-D array with
    one element per distance reported for that type (possibly fewer or more than the
    reflectors of the type), sorted ascending.

    Attributes
    ----------
    type_names : tuple of str
    distances_m : tuple of ndarray
        Smoothed (or raw) distances.
    variances_m2 : tuple of ndarray
        Their variances.
    fresh : tuple of ndarray of bool
        True where the distance was updated by a detection in this frame; False where the
        track is coasting on its prediction.
    velocities_mps : tuple of ndarray, optional
        Measured radial velocity (Doppler) of each distance, positive when it grows; None when
        the source reports none (then the positioning uses the distances only).
    """

    type_names: tuple[str, ...]
    distances_m: tuple[np.ndarray, ...]
    variances_m2: tuple[np.ndarray, ...]
    fresh: tuple[np.ndarray, ...]
    velocities_mps: tuple[np.ndarray, ...] | None = None

    @classmethod
    def from_distances(
        cls, type_names: tuple[str, ...], distances_m, std_m: float = 0.075
    ) -> Fingerprint:
        """A fingerprint of exact (e.g. true) distances with a common standard deviation."""
        d = tuple(np.sort(np.asarray(x, dtype=float).reshape(-1)) for x in distances_m)
        return cls(
            tuple(type_names),
            d,
            tuple(np.full(len(x), std_m**2) for x in d),
            tuple(np.ones(len(x), dtype=bool) for x in d),
        )

    @classmethod
    def from_true(
        cls,
        layout,
        radar_position_m: np.ndarray,
        std_m: float = 0.075,
        visible: np.ndarray | None = None,
    ) -> Fingerprint:
        """The exact fingerprint of a radar position for a :class:`ReflectorLayout`: every
        reflector's distance, or only those of the reflectors ``visible`` (M,) bool marks."""
        dist = layout.distances_m(np.asarray(radar_position_m, dtype=float))
        seen = np.ones(len(dist), bool) if visible is None else np.asarray(visible, bool)
        return cls.from_distances(
            layout.type_names,
            [dist[(layout.type_index == t) & seen] for t in range(len(layout.types))],
            std_m,
        )

    @property
    def count(self) -> int:
        return int(sum(len(d) for d in self.distances_m))

    def fresh_only(self) -> Fingerprint:
        """Only the distances measured in this frame."""
        vel = self.velocities_mps
        return Fingerprint(
            self.type_names,
            tuple(d[f] for d, f in zip(self.distances_m, self.fresh, strict=True)),
            tuple(v[f] for v, f in zip(self.variances_m2, self.fresh, strict=True)),
            tuple(f[f] for f in self.fresh),
            None if vel is None else tuple(v[f] for v, f in zip(vel, self.fresh, strict=True)),
        )
