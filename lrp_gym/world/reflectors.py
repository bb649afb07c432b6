"""Reflector (LRP) types, their radar cross sections and incidence-angle patterns."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

REFLECTOR_KINDS = ("trihedral", "sphere", "luneburg", "van_atta", "point")


def _given(value: float | None, name: str, kind: str) -> float:
    if value is None:
        raise ValueError(f"{name}: a {kind} reflector needs it")
    return float(value)


def rcs_peak_m2(
    kind: str,
    wavelength_m: float,
    *,
    edge_m: float | None = None,
    diameter_m: float | None = None,
    elements: int | None = None,
    element_area_m2: float | None = None,
    rcs_dbsm: float | None = None,
) -> float:
    """Peak (boresight) radar cross section in m^2 of a reflector kind.

    Models
    ------
    - ``trihedral``: triangular trihedral corner, ``4 pi a^4 / (3 lambda^2)``.
    - ``sphere``: optical region, ``pi (d/2)^2`` (independent of wavelength).
    - ``luneburg``: Luneburg lens with a reflective cap, ``4 pi^3 r^4 / lambda^2`` (r = d/2).
    - ``van_atta``: retro-directive array of N patches of effective area A:
      ``4 pi (N A)^2 / lambda^2`` (the flat-plate formula for the whole aperture).
    - ``point``: a fixed ``rcs_dbsm``.
    """
    lam2 = wavelength_m**2
    if kind == "trihedral":
        return 4.0 * np.pi * _given(edge_m, "edge_m", kind) ** 4 / (3.0 * lam2)
    if kind == "sphere":
        return np.pi * (_given(diameter_m, "diameter_m", kind) / 2.0) ** 2
    if kind == "luneburg":
        return 4.0 * np.pi**3 * (_given(diameter_m, "diameter_m", kind) / 2.0) ** 4 / lam2
    if kind == "van_atta":
        n = _given(elements, "elements", kind)
        return 4.0 * np.pi * (n * _given(element_area_m2, "element_area_m2", kind)) ** 2 / lam2
    if kind == "point":
        return float(10.0 ** (_given(rcs_dbsm, "rcs_dbsm", kind) / 10.0))
    raise ValueError(f"unknown reflector kind {kind!r}; expected one of {REFLECTOR_KINDS}")


@dataclass(frozen=True)
class ReflectorType:
    """One distinguishable reflector type.

    Attributes
    ----------
    name : str
        Type label used in configs and fingerprints (e.g. ``"A"``).
    kind : str
        One of :data:`REFLECTOR_KINDS`.
    rcs_m2 : float
        Peak radar cross section at the radar's wavelength.
    half_angle_deg : float or None
        Incidence angle (from the reflector's axis) at which the RCS has dropped by 3 dB;
        ``None`` for an omnidirectional reflector (sphere, point, Luneburg lens).
    cutoff_deg : float
        Beyond this incidence angle the reflector returns nothing.
    """

    name: str
    kind: str
    rcs_m2: float
    half_angle_deg: float | None = None
    cutoff_deg: float = 90.0

    @property
    def rcs_dbsm(self) -> float:
        return float(10.0 * np.log10(self.rcs_m2))

    def pattern(self, cos_incidence: np.ndarray) -> np.ndarray:
        """Power gain (0..1) of the RCS for the cosine of the incidence angle.

        A Gaussian main lobe, -3 dB at ``half_angle_deg``, zero past ``cutoff_deg``.
        """
        cos_incidence = np.asarray(cos_incidence, dtype=float)
        if self.half_angle_deg is None and self.cutoff_deg >= 180.0:
            return np.ones_like(cos_incidence)
        angle = np.degrees(np.arccos(np.clip(cos_incidence, -1.0, 1.0)))
        gain = np.ones_like(angle)
        if self.half_angle_deg is not None:
            gain = 10.0 ** (-0.3 * (angle / self.half_angle_deg) ** 2)
        return np.where(angle <= self.cutoff_deg, gain, 0.0)


@dataclass(frozen=True)
class ReflectorLayout:
    """Reflectors placed in a room.

    Attributes
    ----------
    positions_m : ndarray, shape (M, 3)
        Reflector phase centres.
    type_index : ndarray of int, shape (M,)
        Index into ``types`` for each reflector.
    axes : ndarray, shape (M, 3)
        Unit vectors of each reflector's boresight (where its RCS peaks).
    types : tuple of ReflectorType
        The distinguishable types.
    """

    positions_m: np.ndarray
    type_index: np.ndarray
    axes: np.ndarray
    types: tuple[ReflectorType, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "positions_m", np.asarray(self.positions_m, float).reshape(-1, 3))
        object.__setattr__(self, "type_index", np.asarray(self.type_index, int).reshape(-1))
        axes = np.asarray(self.axes, float).reshape(-1, 3)
        object.__setattr__(self, "axes", axes / np.linalg.norm(axes, axis=1, keepdims=True))

    def __len__(self) -> int:
        return len(self.type_index)

    @property
    def type_names(self) -> tuple[str, ...]:
        return tuple(t.name for t in self.types)

    @property
    def rcs_m2(self) -> np.ndarray:
        """Peak RCS of each reflector, shape (M,)."""
        return np.array([self.types[i].rcs_m2 for i in self.type_index])

    def counts_per_type(self) -> np.ndarray:
        """Number of reflectors of each type, shape (n_types,)."""
        return np.bincount(self.type_index, minlength=len(self.types))

    def effective_rcs_m2(self, radar_positions_m: np.ndarray) -> np.ndarray:
        """RCS each reflector shows towards radar positions (..., 3): shape (..., M)."""
        radar = np.asarray(radar_positions_m, float)[..., None, :]
        to_radar = radar - self.positions_m
        dist = np.linalg.norm(to_radar, axis=-1)
        cos_inc = np.einsum("...mk,mk->...m", to_radar, self.axes) / np.maximum(dist, 1e-12)
        gain = np.empty_like(cos_inc)
        for t, rtype in enumerate(self.types):
            sel = self.type_index == t
            gain[..., sel] = rtype.pattern(cos_inc[..., sel])
        return gain * self.rcs_m2

    def distances_m(self, radar_positions_m: np.ndarray) -> np.ndarray:
        """Slant distances (..., M) from radar positions (..., 3) to each reflector."""
        radar = np.asarray(radar_positions_m, float)[..., None, :]
        return np.linalg.norm(radar - self.positions_m, axis=-1)
