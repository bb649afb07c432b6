"""Reproduction of the paper's positioning experiment along a scenario's path.

Full chain per frame: signal-level radar (multipath) -> CFAR detections -> LRP tracker ->
fingerprint -> look-up table and AMCL. The path is driven at ``robot.max_speed_mps`` with one
frame every ``task.frame_period_s``; AMCL receives the true odometry between consecutive poses
plus the robot's odometry noise (``world.odometry_noise``), drawn from the run's generator.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from lrp_gym.config import ScenarioConfig
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.lut import LookupTable
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.robot import odometry_delta
from lrp_gym.world.trajectory import path_trajectory
from lrp_gym.world.world import World

#: The paper's headline figures for its proof-of-concept scenario.
PAPER = {
    "amcl_mean_error_m": 0.097,
    "lut_failures_m": {9: 3.5, 12: 1.0},  # 1-based positions
    "amcl_converged_after": 6,
    "lut_entries": 6574,
}

CONVERGED_ERROR_M = 0.15


@dataclass
class Reproduction:
    """Per-run, per-position errors of the look-up table and AMCL (metres)."""

    lut_errors_m: np.ndarray  # (runs, K)
    amcl_errors_m: np.ndarray  # (runs, K)
    lut_entries: int
    frame_ms: dict[str, float]
    true_poses: np.ndarray
    amcl_particles: np.ndarray  # (runs, K)
    meta: dict = field(default_factory=dict)

    @property
    def converged_after(self) -> int | None:
        """First 1-based position from which the mean AMCL error stays under 0.15 m."""
        return converged_after(self.amcl_errors_m.mean(axis=0))

    def to_dict(self) -> dict:
        lut_mean = self.lut_errors_m.mean(axis=0)
        amcl_mean = self.amcl_errors_m.mean(axis=0)
        return {
            "positions": int(self.lut_errors_m.shape[1]),
            "runs": int(self.lut_errors_m.shape[0]),
            "lut": {
                "errors_m": lut_mean,
                "std_errors_m": self.lut_errors_m.std(axis=0),
                "mean_error_m": float(lut_mean.mean()),
                "entries": self.lut_entries,
            },
            "amcl": {
                "mean_errors_m": amcl_mean,
                "std_errors_m": self.amcl_errors_m.std(axis=0),
                "mean_error_m": float(amcl_mean.mean()),
                "converged_after": self.converged_after,
                "mean_particles": self.amcl_particles.mean(axis=0),
            },
            "frame_ms": self.frame_ms,
            "paper": PAPER,
            **self.meta,
        }


def converged_after(
    mean_errors_m: np.ndarray, threshold_m: float = CONVERGED_ERROR_M
) -> int | None:
    """First 1-based index from which every later error is below ``threshold_m``; else None."""
    bad = np.flatnonzero(np.asarray(mean_errors_m) >= threshold_m)
    if len(bad) == 0:
        return 1
    return int(bad[-1]) + 2 if bad[-1] + 1 < len(mean_errors_m) else None


def _odometry(world: World, prev: np.ndarray, pose: np.ndarray, frame: int, rng) -> np.ndarray:
    """Noisy odometry from ``prev`` to ``pose`` (zero at the first frame)."""
    if frame == 0:
        return np.zeros(3)
    return world.odometry_noise.sample(odometry_delta(prev, pose), (), rng)


def reproduce(
    cfg: ScenarioConfig,
    runs: int = 10,
    seed: int = 0,
    progress: Callable[[int, dict], None] | None = None,
    true_fingerprints: bool = False,
    estimator: str = "best_k",
) -> Reproduction:
    """Run the full chain ``runs`` times along ``cfg.task.path``.

    Parameters
    ----------
    cfg : ScenarioConfig
        Needs a path of at least two waypoints; ``cfg.radar.noise`` switches thermal noise.
    runs : int
        Independent runs (one ``SeedSequence`` child per run).
    seed : int
        Root seed.
    progress : callable, optional
        Called after each run with its 0-based index and a summary dict.
    true_fingerprints : bool
        Bypass radar and tracker: feed the exact fingerprints (std ``tracking.measurement_std_m``)
        to both methods, to separate positioning from detection errors.
    estimator : {"best_k", "cluster"}
        AMCL's pose estimate: the paper's rule (weighted mean of the 20 best particles within
        15 cm of the best) or the mean of the heaviest cluster.
    """
    from lrp_gym.localization.pipeline import track_and_localize
    from lrp_gym.radar.sensor import RadarSensor
    from lrp_gym.tracking.motion import EgoMotion
    from lrp_gym.tracking.tracker import LrpTracker

    if len(cfg.task.path) < 2:
        raise ValueError("the scenario has no path (task.path needs at least 2 waypoints)")
    world = World.from_config(cfg)
    loc = cfg.localization.model_copy(update={"estimator": estimator})
    traj = path_trajectory(
        np.asarray(cfg.task.path), cfg.robot.max_speed_mps, cfg.task.frame_period_s
    )
    t0 = time.perf_counter()
    lut = LookupTable(world, loc.lut_resolution_m, loc.lut_grid_m, 0.0)
    lut_build_s = time.perf_counter() - t0
    sensor = RadarSensor(world, cfg.radar)
    k = len(traj)
    lut_err = np.zeros((runs, k))
    amcl_err = np.zeros((runs, k))
    n_part = np.zeros((runs, k), dtype=int)
    timing = {"radar": 0.0, "tracking_amcl": 0.0, "lut": 0.0}
    children = np.random.SeedSequence(seed).spawn(runs)
    for run in range(runs):
        rng = np.random.default_rng(children[run])
        tracker = LrpTracker.from_world(world, cfg.tracking)
        amcl = Amcl(world, loc)
        amcl.reset(rng, traj.poses[0] if loc.init == "gaussian" else None)
        prev = traj.poses[0]
        est = None
        for i, (pose, vel) in enumerate(zip(traj.poses, traj.velocities_xy_mps, strict=True)):
            t = time.perf_counter()
            if true_fingerprints:
                fp = Fingerprint.from_true(
                    world.layout, world.radar_position(pose[:2]), cfg.tracking.measurement_std_m
                )
                t1 = time.perf_counter()
                odo = _odometry(world, prev, pose, i, rng)
                est = amcl.update(odo, fp, rng)
            else:
                dets = sensor.measure(pose, vel, rng)
                t1 = time.perf_counter()
                odo = _odometry(world, prev, pose, i, rng)
                fp, est = track_and_localize(
                    world,
                    tracker,
                    amcl,
                    dets,
                    cfg.task.frame_period_s,
                    EgoMotion.from_velocity(vel, pose[2], odo),
                    est,
                    rng,
                    measurements=loc.measurements,
                )
            t2 = time.perf_counter()
            lut_est = lut.query(fp)
            t3 = time.perf_counter()
            prev = pose
            for key, dt in zip(timing, (t1 - t, t2 - t1, t3 - t2), strict=True):
                timing[key] += dt
            lut_err[run, i] = np.hypot(*(lut_est.pose[:2] - pose[:2]))
            amcl_err[run, i] = np.hypot(*(est.pose[:2] - pose[:2]))
            n_part[run, i] = est.n_particles
        if progress is not None:
            progress(
                run,
                {
                    "lut_mean_error_m": float(lut_err[run].mean()),
                    "amcl_mean_error_m": float(amcl_err[run].mean()),
                    "amcl_errors_m": amcl_err[run].copy(),
                },
            )
    frames = runs * k
    frame_ms = {key: 1e3 * v / frames for key, v in timing.items()}
    frame_ms["total"] = sum(frame_ms.values())
    return Reproduction(
        lut_err,
        amcl_err,
        lut.n_entries,
        frame_ms,
        traj.poses,
        n_part,
        meta={
            "scenario": cfg.name,
            "noise": bool(cfg.radar.noise),
            "fingerprints": "true" if true_fingerprints else "radar",
            "estimator": estimator,
            "measurements": loc.measurements,
            "seed": seed,
            "initial_particles": loc.initial_particles,
            "lut_build_s": lut_build_s,
            "lut_ambiguous_entries": int(np.sum(lut.regions_per_entry > 1)),
        },
    )
