"""How often the radar delivers each LRP the way the tracker needs it.

An LRP counts as *delivered* in a frame when some detection lies within ``tolerance_m`` of its
true slant distance and its RCS estimate falls in the tracker's RCS window of the LRP's type
(``peak - rcs_tolerance_db - rcs_pattern_loss_db .. peak + rcs_tolerance_db``, see
:mod:`lrp_gym.tracking.classify`). Poses are drawn uniformly over the free floor (robot radius
as clearance) with a uniform heading and a forward speed uniform in ``[0, max_speed]``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from lrp_gym.config import ScenarioConfig, TrackingConfig
from lrp_gym.radar.detections import Detections
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world.reflector_view import reflector_view
from lrp_gym.world.world import World


@dataclass(frozen=True)
class DetectionRate:
    """Result of :func:`lrp_detection_rate`.

    Attributes
    ----------
    rate : float
        Fraction of (pose, LRP) pairs delivered (range within tolerance and RCS in window).
    range_only_rate : float
        Fraction with a detection within the range tolerance, whatever its RCS.
    median_rcs_error_db : float
        Median of (RCS estimate - peak RCS of the type) over the delivered pairs.
    range_error_std_m : float
        Standard deviation of the range error over the delivered pairs.
    mean_detections : float
        Detections per frame.
    n_poses, n_lrps : int
    per_lrp_rate : tuple of float
        ``rate`` of each LRP, in layout order.
    in_view_rate : float
        ``rate`` over the pairs where the LRP is in view (no obstacle on the line of sight,
        inside its pattern's cutoff, in range): the detection probability the localiser's
        likelihood assumes (``localization.detection_probability``).
    per_lrp_in_view_rate : tuple of float
        ``in_view_rate`` of each LRP (NaN for one never in view).
    """

    rate: float
    range_only_rate: float
    median_rcs_error_db: float
    range_error_std_m: float
    mean_detections: float
    n_poses: int
    n_lrps: int
    per_lrp_rate: tuple[float, ...] = ()
    in_view_rate: float = float("nan")
    per_lrp_in_view_rate: tuple[float, ...] = ()

    def as_dict(self) -> dict:
        return asdict(self)


def random_poses(
    world: World, n: int, rng: np.random.Generator, clearance_m: float, max_speed_mps: float
) -> tuple[np.ndarray, np.ndarray]:
    """``n`` free poses (n, 3) and velocities (n, 2) along their headings."""
    out = np.zeros((0, 2))
    while len(out) < n:
        xy = rng.uniform(0.0, 1.0, (4 * n, 2)) * world.room.size_m[:2]
        out = np.vstack([out, xy[world.room.free(xy, clearance_m)]])
    xy = out[:n]
    th = rng.uniform(-np.pi, np.pi, n)
    speed = rng.uniform(0.0, max_speed_mps, n)
    return np.column_stack([xy, th]), speed[:, None] * np.column_stack([np.cos(th), np.sin(th)])


def lrp_detection_rate(
    cfg: ScenarioConfig,
    n_poses: int = 200,
    seed: int = 0,
    *,
    tolerance_m: float = 0.1,
    fidelity: str | None = None,
) -> DetectionRate:
    """Fraction of the LRPs the radar delivers at random free poses (see the module docstring).

    Parameters
    ----------
    cfg : ScenarioConfig
        Scenario; its radar section is used as is (noise, CFAR, ...).
    n_poses : int
    seed : int
        Seeds both the poses and the radar noise.
    tolerance_m : float
        Largest range error of a detection that counts.
    fidelity : {"signal", "detections"}, optional
        Overrides ``cfg.radar.fidelity``.
    """
    world = World.from_config(cfg)
    radar_cfg = (
        cfg.radar if fidelity is None else cfg.radar.model_copy(update={"fidelity": fidelity})
    )
    sensor = RadarSensor(world, radar_cfg)
    rng = np.random.default_rng(seed)
    poses, vels = random_poses(world, n_poses, rng, cfg.robot.radius_m, cfg.robot.max_speed_mps)
    peak, low, high = _rcs_window(world, cfg.tracking)
    ok, near, rcs_err, rng_err, counts = [], [], [], [], []
    for pose, vel in zip(poses, vels, strict=True):
        det = sensor.measure(pose, vel, rng)
        counts.append(len(det))
        true = world.true_distances_m(pose[:2])
        if len(det) == 0:
            ok.extend([False] * len(true))
            near.extend([False] * len(true))
            continue
        close, good, err = _match(det, true, tolerance_m, low, high)
        near.extend(np.asarray(close.any(axis=1)))
        ok.extend(np.asarray(good.any(axis=1)))
        for m in np.flatnonzero(good.any(axis=1)):
            j = np.flatnonzero(good[m])[np.argmin(np.abs(err[m, good[m]]))]
            rcs_err.append(det.rcs_dbsm[j] - peak[m])
            rng_err.append(err[m, j])
    ok_pairs = np.reshape(ok, (n_poses, len(world.layout)))
    in_view_rate, per_in_view = _in_view_rates(world, poses, ok_pairs)
    return DetectionRate(
        rate=float(np.mean(ok)),
        range_only_rate=float(np.mean(near)),
        median_rcs_error_db=float(np.median(rcs_err)) if rcs_err else float("nan"),
        range_error_std_m=float(np.std(rng_err)) if rng_err else float("nan"),
        mean_detections=float(np.mean(counts)),
        n_poses=int(n_poses),
        n_lrps=len(world.layout),
        per_lrp_rate=tuple(float(r) for r in ok_pairs.mean(axis=0)),
        in_view_rate=in_view_rate,
        per_lrp_in_view_rate=per_in_view,
    )


def _in_view_rates(
    world: World, poses: np.ndarray, ok_pairs: np.ndarray
) -> tuple[float, tuple[float, ...]]:
    """The delivered share ``ok_pairs`` (poses, M) over the pairs whose LRP the pose has in
    view (line of sight, pattern, range), in total and per LRP (NaN for one never in view)."""
    view = reflector_view(
        world.room, world.layout, world.mount_height_m, world.fmcw.max_range_m, poses[:, :2]
    )
    in_view = view.in_view.T  # (poses, M)
    seen = in_view.sum(axis=0)
    per_lrp = (ok_pairs & in_view).sum(axis=0) / np.where(seen > 0, seen, np.nan)
    total = float(ok_pairs[in_view].mean()) if in_view.any() else float("nan")
    return total, tuple(float(r) for r in per_lrp)


def _rcs_window(world: World, tracking: TrackingConfig) -> tuple[np.ndarray, ...]:
    """Per LRP (M,): its type's peak RCS and the tracker's RCS window around it (dBsm)."""
    lay = world.layout
    peak = np.array([t.rcs_dbsm for t in lay.types])[lay.type_index]
    low = peak - tracking.rcs_tolerance_db - tracking.rcs_pattern_loss_db
    return peak, low, peak + tracking.rcs_tolerance_db


def _match(
    det: Detections, true_m: np.ndarray, tolerance_m: float, low: np.ndarray, high: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which detections (D,) lie within the tolerance of each LRP (M,) and which of those have
    an RCS in its window, as (M, D) masks; and the range errors (M, D)."""
    err = det.range_m[None, :] - true_m[:, None]  # (M, D)
    close = np.abs(err) <= tolerance_m
    good = close & (det.rcs_dbsm >= low[:, None]) & (det.rcs_dbsm <= high[:, None])
    return close, good, err
