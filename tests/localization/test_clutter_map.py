"""The clutter map: unmapped static scatterers learnt while localised (issue 16)."""

from __future__ import annotations

import numpy as np
import pytest

import lrp_gym.envs  # noqa: F401  (registers the env ids)
from lrp_gym.config import ClutterMapConfig, load_scenario
from lrp_gym.envs.nav_env import build_config
from lrp_gym.experiments.track_path import ego_motions
from lrp_gym.localization.clutter_map import (
    ClutterMap,
    cross_spread_m,
    fit_point,
    point_hypotheses,
)
from lrp_gym.localization.stack import LocalizationStack
from lrp_gym.perturbations.base import peak_rcs_dbsm
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.trajectory import path_trajectory
from lrp_gym.world.world import World

POINT = np.array([3.2, 1.4, 1.1])  # (x, y, height off the radar plane)


def _l_path(n: int = 24) -> np.ndarray:
    """Radar positions along an L: 2 m east, then 2 m north."""
    t = np.linspace(0.0, 1.0, n // 2)
    leg1 = np.column_stack([0.8 + 2.0 * t, np.full_like(t, 0.8)])
    leg2 = np.column_stack([np.full_like(t, 2.8), 0.8 + 2.0 * t])
    return np.vstack([leg1, leg2])


def _ranges(xy: np.ndarray, point: np.ndarray = POINT) -> np.ndarray:
    return np.sqrt(np.sum((xy - point[:2]) ** 2, axis=1) + point[2] ** 2)


def test_fit_point_recovers_a_point_from_noisy_distances() -> None:
    rng = np.random.default_rng(0)
    xy = _l_path()
    r = _ranges(xy) + rng.normal(0.0, 0.02, len(xy))
    point, rms = fit_point(xy, r)
    assert np.linalg.norm(point - POINT) < 0.1
    assert 0.01 < rms < 0.03  # the residual is the noise, not a misfit


def test_hypotheses_contain_the_point_and_need_a_triangle() -> None:
    rng = np.random.default_rng(1)
    xy = _l_path()
    # Each frame: the point's distance among three one-frame clutter distances.
    frames = [np.sort(np.r_[d, rng.uniform(1.0, 5.0, 3)]) for d in _ranges(xy)]
    cand = point_hypotheses(xy, frames, min_spread_m=0.15)
    assert np.min(np.linalg.norm(cand - POINT, axis=1)) < 1e-6
    line = np.column_stack([np.linspace(0.5, 3.0, 20), np.full(20, 1.0)])
    assert cross_spread_m(line) == pytest.approx(0.0, abs=1e-9)
    assert len(point_hypotheses(line, [np.array([2.0])] * 20, min_spread_m=0.15)) == 0


@pytest.fixture(scope="module")
def world() -> World:
    return World.from_config(load_scenario("ipin2023"))


def _frame(world: World, xy: np.ndarray, extra: list[float]) -> Fingerprint:
    """All reflectors' true distances plus ``extra`` distances, as one type's detections."""
    d = np.r_[world.true_distances_m(xy), extra]
    fp = Fingerprint.from_distances(world.layout.type_names, [d], std_m=0.05)
    return fp


def test_a_static_point_seen_from_several_poses_is_learnt_and_taken_out(world: World) -> None:
    rng = np.random.default_rng(2)
    cmap = ClutterMap(world, ClutterMapConfig())
    xy = _l_path(40)
    for p, d in zip(xy, _ranges(xy), strict=True):
        cmap.update(p, _frame(world, p, [d + rng.normal(0, 0.02), rng.uniform(1.0, 6.0)]))
    assert len(cmap.points) == 1  # the static point; neither the reflectors nor one-frame noise
    assert np.linalg.norm(cmap.points[0] - POINT) < 0.15
    # What the localiser then weighs: every reflector's distance, not the point's.
    here = np.array([2.0, 2.5])
    fp = _frame(world, here, [float(_ranges(here[None])[0])])
    kept = cmap.without_clutter(fp, here).distances_m[0]
    assert len(kept) == len(world.layout)
    assert np.allclose(np.sort(kept), np.sort(world.true_distances_m(here)))


def test_a_reflector_keeps_a_distance_a_clutter_point_shares(world: World) -> None:
    cmap = ClutterMap(world, ClutterMapConfig())
    here = np.array([2.0, 2.5])
    d0 = world.true_distances_m(here)[0]
    # A point at exactly reflector 0's distance from here.
    cmap.add(np.array([here[0], here[1], d0]))
    fp = _frame(world, here, [])
    assert np.allclose(cmap.without_clutter(fp, here).distances_m[0], fp.distances_m[0])


def test_a_point_no_longer_seen_is_forgotten(world: World) -> None:
    cfg = ClutterMapConfig(forget_frames=10)
    cmap = ClutterMap(world, cfg)
    cmap.add(POINT)
    xy = _l_path(40)
    nothing = Fingerprint.from_distances(world.layout.type_names, [[]])
    for k, p in enumerate(xy[:15]):
        cmap.update(p, nothing)
        assert len(cmap.points) == (1 if k < cfg.forget_frames else 0)


def test_a_room_return_the_model_predicts_is_not_clutter(world: World) -> None:
    rng = np.random.default_rng(3)
    cmap = ClutterMap(world, ClutterMapConfig())
    xy = _l_path(40)

    def room_returns(positions: np.ndarray) -> np.ndarray:
        return _ranges(positions)[None, :]  # the model predicts this very point

    for p, d in zip(xy, _ranges(xy), strict=True):
        cmap.update(p, _frame(world, p, [d + rng.normal(0, 0.02)]), room_returns)
    assert len(cmap.points) == 0


def test_the_stack_learns_a_scatterer_and_keeps_it_out_of_amcl() -> None:
    """The patrol, driven on its true trajectory with one unmapped scatterer as strong as a
    reflector: the stack's clutter map finds it, and once it has, the distances AMCL weighs
    no longer contain its return (unless a reflector's distance is the same)."""
    cfg = build_config(
        "ipin2023-patrol",
        {"localization": {"clutter_map": {"enabled": True}}},
        radar_fidelity="detections",
    )
    world = World.from_config(cfg)
    stack = LocalizationStack.from_config(world, cfg)
    traj = path_trajectory(np.asarray(cfg.task.driven_path()), 1.5, cfg.task.frame_period_s)
    egos = ego_motions(traj, world, np.random.default_rng(5))
    # High up: reflectors hang at 3 m, so the tracker only gates returns from 2.7 m on.
    scatterer = np.array([[2.2, 1.9, 3.3]])
    rcs_m2 = np.array([10 ** (peak_rcs_dbsm(world.layout) / 10)])
    rng = np.random.default_rng(6)
    stack.reset(rng, traj.poses[0])
    weighed_after = []
    for k in range(min(120, len(traj.poses))):
        pose = traj.poses[k]
        frame = stack.step(
            pose,
            traj.velocities_xy_mps[k],
            egos[k].odometry,
            rng,
            extra_scatterers=(scatterer, rcs_m2),
        )
        if len(stack.clutter_map.points) and frame.estimate.converged:
            radar = world.radar_position(pose[:2])
            d = float(np.linalg.norm(scatterer[0] - radar))
            if np.min(np.abs(world.true_distances_m(pose[:2]) - d)) > 0.15:
                gated = stack.tracker.gated_fingerprint()
                weighed = stack.clutter_map.declutter(gated, np.zeros(3))
                # Whether a distance within the radar's noise of the scatterer's is left,
                # in what the tracker gated and in what the localiser then weighs.
                before, after = (
                    np.min(np.abs(np.concatenate(f.distances_m) - d), initial=np.inf) < 0.05
                    for f in (gated, weighed)
                )
                weighed_after.append((before, after))
    pts = stack.clutter_map.points
    assert len(pts) == 1
    # Range-only: a point 3 m above the radar is placed loosely over the floor (the distance
    # changes little with the horizontal offset), but it predicts the distances it must.
    truth_h = scatterer[0, 2] - world.mount_height_m
    assert np.linalg.norm(pts[0] - np.r_[scatterer[0, :2], truth_h]) < 0.4
    xy = traj.poses[:120, :2]
    learnt = np.sqrt(np.sum((xy - pts[0, :2]) ** 2, axis=1) + pts[0, 2] ** 2)
    true = np.linalg.norm(world.radar_position(xy) - scatterer[0], axis=1)
    assert np.sqrt(np.mean((learnt - true) ** 2)) < 0.04
    seen = np.array(weighed_after)
    assert len(seen) > 10
    assert seen[:, 0].mean() > 0.8  # the radar keeps delivering it ...
    assert seen[:, 1].mean() < 0.15  # ... and the localiser no longer weighs it
