"""The radar's output: one row per detected target in a frame."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def _f64(a) -> np.ndarray:
    return np.asarray(a, dtype=float).reshape(-1)


@dataclass(frozen=True)
class Detections:
    """Targets detected in one radar frame (all arrays of shape (D,)).

    Attributes
    ----------
    range_m : ndarray
        Radial distance (half the round-trip path length).
    velocity_mps : ndarray
        Radial velocity; positive when the distance grows.
    power_dbm : ndarray
        Received power of the target estimated from its range-Doppler peak.
    rcs_dbsm : ndarray
        Radar cross section from inverting the radar equation with ``power_dbm`` and ``range_m``.
    snr_db : ndarray
        Peak-to-noise ratio in the range-Doppler map.
    """

    range_m: np.ndarray = field(default_factory=lambda: np.zeros(0))
    velocity_mps: np.ndarray = field(default_factory=lambda: np.zeros(0))
    power_dbm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    rcs_dbsm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    snr_db: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        for name in ("range_m", "velocity_mps", "power_dbm", "rcs_dbsm", "snr_db"):
            object.__setattr__(self, name, _f64(getattr(self, name)))
        n = len(self.range_m)
        if any(
            len(getattr(self, k)) != n for k in ("velocity_mps", "power_dbm", "rcs_dbsm", "snr_db")
        ):
            raise ValueError("all Detections arrays must have the same length")

    def __len__(self) -> int:
        return len(self.range_m)

    def select(self, mask_or_index) -> Detections:
        """A subset of the detections (boolean mask or index array)."""
        return Detections(
            self.range_m[mask_or_index],
            self.velocity_mps[mask_or_index],
            self.power_dbm[mask_or_index],
            self.rcs_dbsm[mask_or_index],
            self.snr_db[mask_or_index],
        )

    @staticmethod
    def concatenate(parts: list[Detections]) -> Detections:
        if not parts:
            return Detections()
        return Detections(
            *(
                np.concatenate([getattr(p, k) for p in parts])
                for k in ("range_m", "velocity_mps", "power_dbm", "rcs_dbsm", "snr_db")
            )
        )

    def to_records(self) -> list[dict[str, float]]:
        """JSON-friendly rows."""
        return [
            {
                "range_m": float(r),
                "velocity_mps": float(v),
                "power_dbm": float(p),
                "rcs_dbsm": float(s),
                "snr_db": float(n),
            }
            for r, v, p, s, n in zip(
                self.range_m,
                self.velocity_mps,
                self.power_dbm,
                self.rcs_dbsm,
                self.snr_db,
                strict=True,
            )
        ]
