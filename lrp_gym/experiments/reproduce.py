"""Reproduction of the paper's positioning experiment along a scenario's path.

Full chain per frame, one :class:`~lrp_gym.localization.stack.LocalizationStack`: signal-level
radar (multipath) -> CFAR detections -> AMCL and the LRP tracker (in the configured order) ->
fingerprint -> look-up table. The path is driven at ``robot.max_speed_mps`` with one frame
every ``task.frame_period_s``; AMCL receives the true odometry between consecutive poses plus
the robot's odometry noise (``world.odometry_noise``), drawn from the run's generator after
the frame's radar noise.

With ``localizer="grid"`` the histogram filter (:class:`~lrp_gym.localization.grid.GridFilter`)
runs alongside, with a tracker of its own, on the same detections and odometry. It draws no
random numbers, so the run's generator, hence the detections and AMCL's errors, are exactly
those of a run without it.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from lrp_gym.config import LocalizationConfig, ScenarioConfig
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.factory import Localizer, make_localizer, measured_mixture, radar_link
from lrp_gym.localization.frame_result import FrameResult
from lrp_gym.localization.lut import LookupTable
from lrp_gym.localization.stack import LocalizationStack
from lrp_gym.localization.visibility import RadarLink, ReflectorVisibility
from lrp_gym.radar.detections import Detections
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.tracking.range_prediction import EgoMotion
from lrp_gym.tracking.tracker import LrpTracker
from lrp_gym.world.robot import noisy_odometry
from lrp_gym.world.trajectory import Trajectory, path_trajectory
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
                # each run's mean over the path: a mirror jump in one run shows here
                "run_mean_errors_m": self.amcl_errors_m.mean(axis=1),
                "worst_run_mean_error_m": float(self.amcl_errors_m.mean(axis=1).max()),
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


@dataclass
class _Bench:
    """What every run shares: world, drive, radar, table (and build time), link and AMCL."""

    cfg: ScenarioConfig
    loc: LocalizationConfig
    world: World
    traj: Trajectory
    sensor: RadarSensor
    lut: LookupTable
    lut_build_s: float
    true_fingerprints: bool
    with_grid: bool
    link: RadarLink | None
    amcl: Amcl

    @classmethod
    def build(
        cls, cfg: ScenarioConfig, estimator: str, true_fingerprints: bool, with_grid: bool
    ) -> _Bench:
        world = World.from_config(cfg)
        loc = measured_mixture(cfg).model_copy(update={"estimator": estimator})
        traj = path_trajectory(
            np.asarray(cfg.task.path), cfg.robot.max_speed_mps, cfg.task.frame_period_s
        )
        t0 = time.perf_counter()
        lut = LookupTable(world, loc.lut_resolution_m, loc.lut_grid_m, 0.0)
        lut_build_s = time.perf_counter() - t0
        sensor = RadarSensor(world, cfg.radar)
        link = radar_link(cfg, sensor)  # and its survey: once, not per run
        amcl = Amcl(world, loc, link)
        args = (lut, lut_build_s, true_fingerprints, with_grid, link, amcl)
        return cls(cfg, loc, world, traj, sensor, *args)

    def stack(self, localizer: Localizer, lut: LookupTable | None) -> LocalizationStack:
        """A fresh stack (new tracker) around ``localizer`` on the shared radar."""
        cfg = self.cfg
        return LocalizationStack(
            self.world,
            self.sensor,
            LrpTracker.from_world(self.world, cfg.tracking),
            localizer,
            lut,
            dt_s=cfg.task.frame_period_s,
            measurements=cfg.localization.measurements,
        )

    def stacks(self) -> list[LocalizationStack]:
        """AMCL (sharing the prototype's model and grids) with the table; with the grid filter,
        a second stack on the same frames."""
        out = [self.stack(self.amcl.spawn(), self.lut)]
        if self.with_grid:
            grid_loc = self.loc.model_copy(update={"method": "grid"})
            out.append(self.stack(make_localizer(self.world, grid_loc, self.link), None))
        return out

    def frame(
        self, pose: np.ndarray, vel: np.ndarray, rng: np.random.Generator
    ) -> Detections | Fingerprint:
        """This frame's radar detections, or the exact fingerprint of the reflectors in view."""
        if self.true_fingerprints:
            return Fingerprint.from_true(
                self.world.layout,
                self.world.radar_position(pose[:2]),
                self.cfg.tracking.measurement_std_m,
                ReflectorVisibility.of(self.world).visible(pose[None, :2])[:, 0],
            )
        return self.sensor.measure(pose, vel, rng)


@dataclass
class _RunErrors:
    """Per-position errors (m) and particle counts of one run, and its wall time per stage."""

    lut: np.ndarray
    amcl: np.ndarray
    grid: np.ndarray | None
    particles: np.ndarray
    timing_s: dict[str, float]


def _run(bench: _Bench, rng: np.random.Generator) -> _RunErrors:
    """One drive along the path: every frame through the stack(s)."""
    poses, vels = bench.traj.poses, bench.traj.velocities_xy_mps
    k = len(poses)
    out = _RunErrors(
        lut=np.zeros(k),
        amcl=np.zeros(k),
        grid=np.zeros(k) if bench.with_grid else None,
        particles=np.zeros(k, dtype=int),
        timing_s=dict.fromkeys(_timing_keys(bench.with_grid), 0.0),
    )
    stacks = bench.stacks()
    start = poses[0] if bench.loc.init == "gaussian" else None
    for stack in stacks:
        stack.reset(rng, start)
    prev = None
    for i, (pose, vel) in enumerate(zip(poses, vels, strict=True)):
        t = time.perf_counter()
        frame = bench.frame(pose, vel, rng)
        out.timing_s["radar"] += time.perf_counter() - t
        # The odometry is drawn after the radar frame (the env draws it before: its
        # perturbations may change it before the radar sees the moved robot).
        odo = noisy_odometry(bench.world.odometry_noise, prev, pose, rng)
        ego = EgoMotion.from_velocity(vel, pose[2], odo)
        res = stacks[0].localize(frame, ego, rng)
        out.timing_s["tracking_amcl"] += res.elapsed_s["tracking_localization"]
        out.timing_s["lut"] += res.elapsed_s["lut"]
        _record(out, i, pose, res)
        if out.grid is not None:  # with_grid: the second stack is the grid filter
            # Draws nothing from rng: AMCL's numbers are those of a run without it.
            grid = stacks[1].localize(frame, ego, rng)
            out.timing_s["tracking_grid"] += grid.elapsed_s["tracking_localization"]
            out.grid[i] = np.hypot(*(grid.localizer_estimate.pose[:2] - pose[:2]))
        prev = pose
    return out


def _timing_keys(with_grid: bool) -> tuple[str, ...]:
    keys = ("radar", "tracking_amcl", "lut")
    return (*keys, "tracking_grid") if with_grid else keys


def _record(out: _RunErrors, i: int, pose: np.ndarray, res: FrameResult) -> None:
    """The table's and AMCL's position errors at frame ``i``."""
    est, lut = res.localizer_estimate, res.lut_estimate
    if lut is None:
        raise RuntimeError("the first stack of reproduce-paper always has the look-up table")
    out.lut[i] = np.hypot(*(lut.pose[:2] - pose[:2]))
    out.amcl[i] = np.hypot(*(est.pose[:2] - pose[:2]))
    out.particles[i] = est.n_particles


def run_summary(run: _RunErrors) -> dict:
    """What ``progress`` receives after a run."""
    info = {
        "lut_mean_error_m": float(run.lut.mean()),
        "amcl_mean_error_m": float(run.amcl.mean()),
        "amcl_errors_m": run.amcl.copy(),
    }
    if run.grid is not None:
        info["grid_mean_error_m"] = float(run.grid.mean())
    return info


def reproduce(
    cfg: ScenarioConfig,
    runs: int = 10,
    seed: int = 0,
    progress: Callable[[int, dict], None] | None = None,
    true_fingerprints: bool = False,
    estimator: str = "best_k",
    localizer: str = "amcl",
    runner: Callable[[Callable, list], list] | None = None,
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
    runner : callable, optional
        ``runner(run_unit, [(key, RunUnit), ...])`` returns the runs' results in order (e.g.
        :func:`lrp_gym.experiments.cluster.run_units` on Ray; ``progress`` is then its job).
    """
    if localizer not in ("amcl", "grid"):
        raise ValueError(f"localizer must be amcl or grid, got {localizer!r}")
    if len(cfg.task.path) < 2:
        raise ValueError("the scenario has no path (task.path needs at least 2 waypoints)")
    bench = _Bench.build(cfg, estimator, true_fingerprints, localizer == "grid")
    if runner is not None:
        units = [
            RunUnit(cfg, estimator, true_fingerprints, localizer, seed, runs, i)
            for i in range(runs)
        ]
        results = runner(run_unit, [(f"run {i}", u) for i, u in enumerate(units)])
        return _reproduction(bench, results, seed, estimator, localizer)
    results = []
    for run, child in enumerate(np.random.SeedSequence(seed).spawn(runs)):
        results.append(_run(bench, np.random.default_rng(child)))
        if progress is not None:
            progress(run, run_summary(results[-1]))
    return _reproduction(bench, results, seed, estimator, localizer)


@dataclass(frozen=True)
class RunUnit:
    """Run ``run`` of ``runs`` of :func:`reproduce`: a unit of work on its own, seeded by the
    ``run``-th child of ``SeedSequence(seed)`` as in the one-process loop."""

    cfg: ScenarioConfig
    estimator: str
    true_fingerprints: bool
    localizer: str
    seed: int
    runs: int
    run: int


_BENCHES: dict[str, _Bench] = {}  # a worker builds the world and table once per scenario


def run_unit(u: RunUnit) -> _RunErrors:
    """One run of :func:`reproduce` (a Ray task; the bench is cached in the worker)."""
    key = json.dumps([u.cfg.to_dict(), u.estimator, u.true_fingerprints, u.localizer], default=str)
    if key not in _BENCHES:
        _BENCHES.clear()
        _BENCHES[key] = _Bench.build(u.cfg, u.estimator, u.true_fingerprints, u.localizer == "grid")
    child = np.random.SeedSequence(u.seed).spawn(u.runs)[u.run]
    return _run(_BENCHES[key], np.random.default_rng(child))


def run_to_json(r: _RunErrors) -> dict:
    """One run's errors as JSON values (exact floats)."""
    return {
        "lut": r.lut.tolist(),
        "amcl": r.amcl.tolist(),
        "grid": None if r.grid is None else r.grid.tolist(),
        "particles": r.particles.tolist(),
        "timing_s": dict(r.timing_s),
    }


def run_from_json(d: dict) -> _RunErrors:
    """The inverse of :func:`run_to_json`."""
    grid = None if d["grid"] is None else np.asarray(d["grid"], dtype=float)
    lut, amcl = (np.asarray(d[key], dtype=float) for key in ("lut", "amcl"))
    return _RunErrors(lut, amcl, grid, np.asarray(d["particles"], dtype=int), dict(d["timing_s"]))


def _reproduction(
    bench: _Bench, results: list[_RunErrors], seed: int, estimator: str, localizer: str
) -> Reproduction:
    """Stack the runs' errors and add what the run was."""
    frames = len(results) * len(bench.traj)
    frame_ms = {
        key: 1e3 * sum(r.timing_s[key] for r in results) / frames
        for key in _timing_keys(bench.with_grid)
    }
    frame_ms["total"] = sum(frame_ms.values())
    grids = [r.grid for r in results if r.grid is not None]
    grid = np.stack(grids) if bench.with_grid else None
    cfg, loc, lut = bench.cfg, bench.loc, bench.lut
    return Reproduction(
        np.stack([r.lut for r in results]),
        np.stack([r.amcl for r in results]),
        lut.n_entries,
        frame_ms,
        bench.traj.poses,
        np.stack([r.particles for r in results]),
        meta={
            "scenario": cfg.name,
            "noise": bool(cfg.radar.noise),
            "fingerprints": "true" if bench.true_fingerprints else "radar",
            "estimator": estimator,
            "measurements": loc.measurements,
            "seed": seed,
            "initial_particles": loc.initial_particles,
            "lut_build_s": bench.lut_build_s,
            "lut_ambiguous_entries": int(np.sum(lut.regions_per_entry > 1)),
            "localizer": localizer,
        },
        grid_errors_m=grid,
    )
