"""Drive a scenario's path through the radar chain, the tracker and AMCL; score against the truth."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from lrp_gym.config import ScenarioConfig
from lrp_gym.localization.stack import LocalizationStack
from lrp_gym.radar.detections import Detections
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.tracking.metrics import SwapCounter, per_type_errors_m
from lrp_gym.tracking.range_prediction import EgoMotion
from lrp_gym.world.robot import noisy_odometry
from lrp_gym.world.trajectory import Trajectory, path_trajectory
from lrp_gym.world.world import World


def match_to_truth(
    estimates_by_type: tuple[np.ndarray, ...], truth_m: np.ndarray, type_index: np.ndarray
) -> np.ndarray:
    """The estimate matched to each reflector (Hungarian on |diff| per type), NaN if none."""
    out = np.full(len(truth_m), np.nan)
    for t, est in enumerate(estimates_by_type):
        refl = np.flatnonzero(type_index == t)
        est = np.asarray(est, dtype=float)
        if len(est) == 0 or len(refl) == 0:
            continue
        rows, cols = linear_sum_assignment(np.abs(est[:, None] - truth_m[refl][None, :]))
        out[refl[cols]] = est[rows]
    return out


@dataclass
class TrackRun:
    """Per-frame record and summary of one drive along the path.

    Attributes
    ----------
    trajectory : Trajectory
    truth_m : ndarray (K, M)
        True distances.
    raw_m, tracked_m : ndarray (K, M)
        RCS-gated detection and tracked distance matched to each reflector (NaN: none).
    tracked_fresh : ndarray of bool (K, M)
        Whether the matched tracked distance was measured in that frame.
    detections : list of Detections
    fingerprints : list of Fingerprint
    summary : dict
        ``frames``, ``raw_rmse_m``, ``tracked_rmse_m``, ``swaps``, ``missed_frames``.
    """

    trajectory: Trajectory
    truth_m: np.ndarray
    raw_m: np.ndarray
    tracked_m: np.ndarray
    tracked_fresh: np.ndarray
    detections: list[Detections]
    fingerprints: list[Fingerprint]
    summary: dict


def ego_motions(trajectory: Trajectory, world: World, rng: np.random.Generator) -> list[EgoMotion]:
    """What the robot's odometry reports at each frame of a drive (noisy, as in the env).

    The speed is the true signed forward speed; the odometry since the previous frame is the
    true ``(rot1, trans, rot2)`` plus ``world.odometry_noise`` (zero in the first frame).
    """
    poses, vel = trajectory.poses, trajectory.velocities_xy_mps
    noise = world.odometry_noise
    return [
        EgoMotion.from_velocity(
            vel[k], poses[k, 2], noisy_odometry(noise, poses[k - 1] if k else None, poses[k], rng)
        )
        for k in range(len(trajectory))
    ]


def run_path(
    cfg: ScenarioConfig, seed: int = 0, *, use_ego: bool = True, use_prior: bool = True
) -> TrackRun:
    """Drive ``cfg.task.path`` at ``cfg.robot.max_speed_mps``, one radar frame per period.

    raw RMSE: per frame, the detections inside a type's RCS/range window matched one-to-one
    to that type's true distances; tracked RMSE: the same for the tracker's fingerprint;
    ``swaps``: frames where a confirmed track changed reflector (:class:`SwapCounter`);
    ``missed_frames``: frames where some reflector had no fresh tracked distance.
    AMCL runs alongside, as in the env (one :class:`~lrp_gym.localization.stack.LocalizationStack`).
    With ``use_prior`` its prediction identifies the reflectors (:mod:`lrp_gym.tracking.prior`);
    with ``use_ego`` the tracker gets the robot's (noisy) odometry and predicts static points
    (:mod:`lrp_gym.tracking.range_prediction`), else the paper's constant-velocity model.
    """
    if len(cfg.task.path) < 2:
        raise ValueError("task.path needs at least two waypoints")
    world = World.from_config(cfg)
    stack = LocalizationStack.from_config(world, cfg, map_aided=use_prior, use_ego=use_ego)
    tracker = stack.tracker
    dt = cfg.task.frame_period_s
    traj = path_trajectory(np.asarray(cfg.task.path), cfg.robot.max_speed_mps, dt)
    rng = np.random.default_rng(seed)
    odo_rng = np.random.default_rng([seed, 1])  # odometry noise apart from the radar's
    ego = ego_motions(traj, world, odo_rng)
    stack.reset(rng, traj.poses[0] if cfg.localization.init == "gaussian" else None)
    ti = world.layout.type_index
    n_types = len(world.layout.types)
    counts = world.layout.counts_per_type()
    truth = world.true_distances_m(traj.poses[:, :2])
    raw, tracked = np.full_like(truth, np.nan), np.full_like(truth, np.nan)
    fresh = np.zeros(truth.shape, dtype=bool)
    swaps = SwapCounter(ti)
    raw_err, trk_err, dets, fps = [], [], [], []
    missed = 0
    for k in range(len(traj)):
        frame = stack.step(traj.poses[k], traj.velocities_xy_mps[k], ego[k].odometry, rng)
        det, fp = frame.detections, frame.fingerprint
        if det is None:  # the path drive never skips the radar
            raise RuntimeError(f"frame {k}: the stack returned no detections")
        cls = tracker.classifier.classify(det)
        gated = tuple(det.range_m[cls == t] for t in range(n_types))
        raw[k] = match_to_truth(gated, truth[k], ti)
        tracked[k] = match_to_truth(fp.distances_m, truth[k], ti)
        fresh_match = match_to_truth(fp.fresh_only().distances_m, truth[k], ti)
        fresh[k] = np.isfinite(fresh_match) & (fresh_match == tracked[k])
        raw_err.append(per_type_errors_m(gated, truth[k], ti))
        trk_err.append(per_type_errors_m(fp.distances_m, truth[k], ti))
        swaps.update(tracker.tracks, truth[k])
        missed += any(int(f.sum()) < n for f, n in zip(fp.fresh, counts, strict=True))
        dets.append(det)
        fps.append(fp)
    summary = {
        "frames": len(traj),
        "raw_rmse_m": _rmse(raw_err),
        "tracked_rmse_m": _rmse(trk_err),
        "swaps": swaps.swaps,
        "missed_frames": missed,
    }
    return TrackRun(traj, truth, raw, tracked, fresh, dets, fps, summary)


def _rmse(parts: list[np.ndarray]) -> float:
    e = np.concatenate(parts) if parts else np.zeros(0)
    return float(np.sqrt(np.mean(e**2))) if len(e) else float("nan")
