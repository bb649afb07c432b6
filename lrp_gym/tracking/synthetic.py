"""Synthetic detection streams for testing and benchmarking the tracker without the radar.

Each frame holds the reflectors' direct paths (true distance plus Gaussian noise, radial
velocity from the motion, RCS from the incidence pattern plus noise), each missed with a
probability, plus uniformly scattered clutter with reflector-like RCS and, optionally, a
strong wall-like return whose range sweeps through one reflector's distance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lrp_gym.radar.detections import Detections
from lrp_gym.world.trajectory import Trajectory
from lrp_gym.world.world import World


@dataclass(frozen=True)
class WallReturn:
    """A strong return whose range crosses reflector ``reflector``'s distance.

    Attributes
    ----------
    reflector : int
        Index of the reflector whose distance it crosses.
    crossing_frame : int
        Frame at which both ranges are equal.
    rate_mps : float
        Radial velocity of the wall return relative to the reflector's (its range moves by
        ``rate_mps * dt`` per frame *relative to* the reflector distance).
    frames : int
        Number of frames it is present, centred on ``crossing_frame``.
    rcs_offset_db : float
        Its RCS relative to the reflector type's peak.
    """

    reflector: int
    crossing_frame: int
    rate_mps: float = 1.5
    frames: int = 8
    rcs_offset_db: float = 4.0


def radial_velocities_mps(world: World, xy: np.ndarray, velocity_xy_mps: np.ndarray) -> np.ndarray:
    """Rate of change (K, M) of each reflector distance for robot positions and velocities (K, 2)."""
    radar = world.radar_position(xy)
    diff = radar[:, None, :] - world.layout.positions_m[None, :, :]
    dist = np.linalg.norm(diff, axis=-1)
    return np.einsum("kmj,kj->km", diff[..., :2], velocity_xy_mps) / dist


def synthetic_stream(
    world: World,
    trajectory: Trajectory,
    rng: np.random.Generator,
    *,
    range_std_m: float = 0.02,
    velocity_std_mps: float = 0.05,
    rcs_std_db: float = 1.5,
    miss_probability: float = 0.2,
    clutter_per_frame: float = 2.0,
    clutter_range_m: tuple[float, float] = (0.5, 7.0),
    wall: WallReturn | None = None,
    dropouts: dict[int, tuple[int, int]] | None = None,
) -> tuple[list[Detections], np.ndarray]:
    """Detections for every frame of ``trajectory`` and the true distances.

    Parameters
    ----------
    world : World
    trajectory : Trajectory
    rng : numpy.random.Generator
    range_std_m, velocity_std_mps, rcs_std_db : float
        Measurement noise of the reflector detections.
    miss_probability : float
        Chance that a reflector is not detected in a frame.
    clutter_per_frame : float
        Mean number (Poisson) of clutter detections per frame; their RCS is drawn around the
        peak RCS of a random reflector type, so the RCS window cannot remove them.
    clutter_range_m : (float, float)
        Range interval of the clutter.
    wall : WallReturn, optional
    dropouts : dict, optional
        ``{reflector: (first_frame, n_frames)}``: reflector not detected in those frames.

    Returns
    -------
    detections : list of Detections, one per frame
    true_distances_m : ndarray, shape (K, M)
    """
    xy = trajectory.poses[:, :2]
    truth = world.true_distances_m(xy)
    rates = radial_velocities_mps(world, xy, trajectory.velocities_xy_mps)
    rcs_true = 10.0 * np.log10(
        np.maximum(world.layout.effective_rcs_m2(world.radar_position(xy)), 1e-30)
    )
    peaks = np.array([t.rcs_dbsm for t in world.layout.types])
    noise = (range_std_m, velocity_std_mps, rcs_std_db)
    frames: list[Detections] = []
    for k in range(truth.shape[0]):
        seen = _seen(rng, rcs_true[k], miss_probability, k, dropouts)
        rng_m, vel, rcs = _reflector_returns(rng, truth[k], rates[k], rcs_true[k], seen, noise)
        _add_clutter(rng, rng_m, vel, rcs, clutter_per_frame, clutter_range_m, peaks)
        if wall is not None and abs(k - wall.crossing_frame) <= wall.frames // 2:
            t_rel = trajectory.times_s[k] - trajectory.times_s[wall.crossing_frame]
            m = wall.reflector
            rng_m.append(truth[k, m] + wall.rate_mps * t_rel + rng.normal(0.0, range_std_m))
            vel.append(rates[k, m] + wall.rate_mps + rng.normal(0.0, velocity_std_mps))
            rcs.append(peaks[world.layout.type_index[m]] + wall.rcs_offset_db)
        frames.append(_shuffled_detections(rng, rng_m, vel, rcs))
    return frames, truth


def _seen(
    rng: np.random.Generator,
    rcs_true_db: np.ndarray,
    miss_probability: float,
    k: int,
    dropouts: dict[int, tuple[int, int]] | None,
) -> np.ndarray:
    """Which reflectors (M,) are detected in frame ``k``: not missed, visible, not dropped out."""
    seen = rng.random(len(rcs_true_db)) >= miss_probability
    seen &= np.isfinite(rcs_true_db) & (rcs_true_db > -100.0)
    for m, (first, count) in (dropouts or {}).items():
        if first <= k < first + count:
            seen[m] = False
    return seen


def _reflector_returns(
    rng: np.random.Generator,
    truth_m: np.ndarray,
    rates_mps: np.ndarray,
    rcs_true_db: np.ndarray,
    seen: np.ndarray,
    noise: tuple[float, float, float],
) -> tuple[list[float], list[float], list[float]]:
    """Noisy range, radial velocity and RCS of the seen reflectors (lists, to append to)."""
    range_std_m, velocity_std_mps, rcs_std_db = noise
    n = int(seen.sum())
    rng_m = list(truth_m[seen] + rng.normal(0.0, range_std_m, n))
    vel = list(rates_mps[seen] + rng.normal(0.0, velocity_std_mps, n))
    rcs = list(rcs_true_db[seen] + rng.normal(0.0, rcs_std_db, n))
    return rng_m, vel, rcs


def _add_clutter(
    rng: np.random.Generator,
    rng_m: list[float],
    vel: list[float],
    rcs: list[float],
    clutter_per_frame: float,
    clutter_range_m: tuple[float, float],
    peaks_dbsm: np.ndarray,
) -> None:
    """Append a Poisson number of clutter detections with the RCS of a random reflector type."""
    n_clutter = int(rng.poisson(clutter_per_frame))
    rng_m += list(rng.uniform(*clutter_range_m, n_clutter))
    vel += list(rng.uniform(-2.0, 2.0, n_clutter))
    rcs += list(
        peaks_dbsm[rng.integers(0, len(peaks_dbsm), n_clutter)] + rng.normal(0.0, 2.0, n_clutter)
    )


def _shuffled_detections(
    rng: np.random.Generator, rng_m: list[float], vel: list[float], rcs: list[float]
) -> Detections:
    """The frame's detections in random order (the radar reports in no particular order)."""
    order = rng.permutation(len(rng_m))
    r = np.asarray(rng_m)[order]
    return Detections(
        range_m=r,
        velocity_mps=np.asarray(vel)[order],
        power_dbm=np.zeros(len(r)),
        rcs_dbsm=np.asarray(rcs)[order],
        snr_db=np.full(len(r), 20.0),
    )
