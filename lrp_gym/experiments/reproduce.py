"""Reproduction of the paper's positioning experiment along a scenario's path.

Full chain per frame: signal-level radar (multipath) -> CFAR detections -> LRP tracker ->
fingerprint -> look-up table and AMCL. The path is driven at ``robot.max_speed_mps`` with one
frame every ``task.frame_period_s``; AMCL receives the true odometry between consecutive poses
plus the robot's odometry noise (``world.odometry_noise``), drawn from the run's generator.

With ``localizer="grid"`` the histogram filter (:class:`~lrp_gym.localization.grid.GridFilter`)
runs alongside, with a tracker of its own, on the same detections and odometry. It draws no
random numbers, so the run's generator, hence the detections and AMCL's errors, are exactly
those of a run without it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from lrp_gym.config import ScenarioConfig
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.estimate import PoseEstimate
from lrp_gym.localization.factory import Localizer, make_localizer
from lrp_gym.localization.lut import LookupTable
from lrp_gym.radar.detections import Detections
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.tracking.motion import EgoMotion
from lrp_gym.tracking.tracker import LrpTracker
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
    grid_errors_m: np.ndarray | None = None  # (runs, K), with localizer="grid"

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
            **self._grid_dict(),
        }

    def _grid_dict(self) -> dict:
        if self.grid_errors_m is None:
            return {}
        mean = self.grid_errors_m.mean(axis=0)
        return {
            "grid": {
                "mean_errors_m": mean,
                "std_errors_m": self.grid_errors_m.std(axis=0),
                "mean_error_m": float(mean.mean()),
                "converged_after": converged_after(mean),
            }
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


@dataclass
class _Chain:
    """Identification and positioning of one localiser: its tracker, itself, its estimate."""

    tracker: LrpTracker
    localizer: Localizer
    estimate: PoseEstimate | None = None

    def step(
        self,
        world: World,
        cfg: ScenarioConfig,
        frame: Detections | Fingerprint,
        ego: EgoMotion,
        rng: np.random.Generator,
    ) -> Fingerprint:
        """One frame: radar detections through the tracker, or a true fingerprint directly."""
        from lrp_gym.localization.pipeline import track_and_localize

        if isinstance(frame, Fingerprint):
            self.estimate = self.localizer.update(ego.odometry, frame, rng)
            return frame
        fp, self.estimate = track_and_localize(
            world,
            self.tracker,
            self.localizer,
            frame,
            cfg.task.frame_period_s,
            ego,
            self.estimate,
            rng,
            measurements=cfg.localization.measurements,
        )
        return fp


def reproduce(
    cfg: ScenarioConfig,
    runs: int = 10,
    seed: int = 0,
    progress: Callable[[int, dict], None] | None = None,
    true_fingerprints: bool = False,
    estimator: str = "best_k",
    localizer: str = "amcl",
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
    localizer : {"amcl", "grid"}
        ``grid``: run the histogram filter too, on the same detections and odometry (its
        errors in ``grid_errors_m``; AMCL's are unchanged).
    """
    from lrp_gym.radar.sensor import RadarSensor

    if localizer not in ("amcl", "grid"):
        raise ValueError(f"localizer must be amcl or grid, got {localizer!r}")
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
    grid_err = np.zeros((runs, k)) if localizer == "grid" else None
    n_part = np.zeros((runs, k), dtype=int)
    timing = {"radar": 0.0, "tracking_amcl": 0.0, "lut": 0.0}
    if grid_err is not None:
        timing["tracking_grid"] = 0.0
    children = np.random.SeedSequence(seed).spawn(runs)
    for run in range(runs):
        rng = np.random.default_rng(children[run])
        start = traj.poses[0] if loc.init == "gaussian" else None
        chains = [_Chain(LrpTracker.from_world(world, cfg.tracking), Amcl(world, loc))]
        if grid_err is not None:
            grid_loc = loc.model_copy(update={"method": "grid"})
            chains.append(
                _Chain(LrpTracker.from_world(world, cfg.tracking), make_localizer(world, grid_loc))
            )
        for chain in chains:
            chain.localizer.reset(rng, start)
        prev = traj.poses[0]
        for i, (pose, vel) in enumerate(zip(traj.poses, traj.velocities_xy_mps, strict=True)):
            t = time.perf_counter()
            if true_fingerprints:
                frame = Fingerprint.from_true(
                    world.layout, world.radar_position(pose[:2]), cfg.tracking.measurement_std_m
                )
            else:
                frame = sensor.measure(pose, vel, rng)
            t1 = time.perf_counter()
            ego = EgoMotion.from_velocity(vel, pose[2], _odometry(world, prev, pose, i, rng))
            fp = chains[0].step(world, cfg, frame, ego, rng)
            t2 = time.perf_counter()
            lut_est = lut.query(fp)
            t3 = time.perf_counter()
            for key, dt in zip(timing, (t1 - t, t2 - t1, t3 - t2), strict=False):
                timing[key] += dt
            if grid_err is not None:
                chains[1].step(world, cfg, frame, ego, rng)  # draws nothing from rng
                timing["tracking_grid"] += time.perf_counter() - t3
                grid_err[run, i] = np.hypot(*(chains[1].estimate.pose[:2] - pose[:2]))
            prev = pose
            est = chains[0].estimate
            lut_err[run, i] = np.hypot(*(lut_est.pose[:2] - pose[:2]))
            amcl_err[run, i] = np.hypot(*(est.pose[:2] - pose[:2]))
            n_part[run, i] = est.n_particles
        if progress is not None:
            info = {
                "lut_mean_error_m": float(lut_err[run].mean()),
                "amcl_mean_error_m": float(amcl_err[run].mean()),
                "amcl_errors_m": amcl_err[run].copy(),
            }
            if grid_err is not None:
                info["grid_mean_error_m"] = float(grid_err[run].mean())
            progress(run, info)
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
            "localizer": localizer,
        },
        grid_errors_m=grid_err,
    )
