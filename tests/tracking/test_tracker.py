"""LRP tracker on synthetic detection streams: accuracy, identity, re-acquisition, limits."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.radar.detections import Detections
from lrp_gym.tracking import LrpTracker
from lrp_gym.tracking.metrics import SwapCounter, per_type_errors_m
from lrp_gym.tracking.synthetic import WallReturn, synthetic_stream
from lrp_gym.world import World
from lrp_gym.world.trajectory import path_trajectory

DT = 0.1
LOOP = [[0.75, 0.75], [4.25, 0.75], [4.25, 4.25], [0.75, 4.25], [0.75, 1.25], [3.5, 2.5]]


@pytest.fixture(scope="module")
def two_type_world(paper_cfg):
    """The paper room with two types: 0 dBsm trihedrals (A) and 12 dBsm ones (B), 2 + 2."""
    data = paper_cfg.to_dict()
    data["reflectors"]["types"]["B"] = {"kind": "trihedral", "edge_m": 0.1}
    for i in (1, 3):
        data["reflectors"]["layout"][i]["type"] = "B"
    cfg = paper_cfg.from_dict(data)
    return cfg, World.from_config(cfg)


@pytest.fixture(scope="module")
def loop():
    return path_trajectory(LOOP, 1.0, DT)


def run(world, cfg, frames):
    tracker = LrpTracker.from_world(world, cfg.tracking)
    fps, views = [], []
    for det in frames:
        fps.append(tracker.update(det, DT))
        views.append(tracker.tracks)
    return tracker, fps, views


def rmse(errors):
    e = np.concatenate(errors)
    return float(np.sqrt(np.mean(e**2)))


def test_tracked_beats_raw_detections(two_type_world, loop):
    cfg, world = two_type_world
    raw_all, trk_all = [], []
    for seed in range(3):
        frames, truth = synthetic_stream(
            world, loop, np.random.default_rng(seed), wall=WallReturn(0, 40)
        )
        tracker, fps, _ = run(world, cfg, frames)
        ti = world.layout.type_index
        for k, (det, fp) in enumerate(zip(frames, fps, strict=True)):
            cls = tracker.classifier.classify(det)
            raw_all.append(per_type_errors_m([det.range_m[cls == t] for t in (0, 1)], truth[k], ti))
            trk_all.append(per_type_errors_m(fp.distances_m, truth[k], ti))
    raw, trk = rmse(raw_all), rmse(trk_all)
    assert trk < 0.6 * raw
    # Most tracked distances are at the measurement-noise level.
    assert np.median(np.abs(np.concatenate(trk_all))) < 0.03


def test_types_never_mix(two_type_world, loop):
    """A type's reported distances follow that type's reflectors, not the other type's."""
    cfg, world = two_type_world
    frames, truth = synthetic_stream(world, loop, np.random.default_rng(7), clutter_per_frame=1.0)
    _, fps, _ = run(world, cfg, frames)
    ti = world.layout.type_index
    hits = total = 0
    for k, fp in enumerate(fps[5:], start=5):
        for t in (0, 1):
            for d, f in zip(fp.distances_m[t], fp.fresh[t], strict=True):
                if not f:
                    continue
                own = np.min(np.abs(truth[k, ti == t] - d))
                other = np.min(np.abs(truth[k, ti != t] - d))
                total += 1
                hits += own <= 0.1 or own < other
    assert total > 300
    assert hits / total > 0.97


def test_no_swaps_without_clutter(two_type_world, loop):
    cfg, world = two_type_world
    frames, truth = synthetic_stream(world, loop, np.random.default_rng(3), clutter_per_frame=0.0)
    _, _, views = run(world, cfg, frames)
    counter = SwapCounter(world.layout.type_index)
    for k, v in enumerate(views):
        counter.update(v, truth[k])
    assert counter.swaps == 0


def test_wall_return_does_not_steal_the_track(two_type_world, loop):
    cfg, world = two_type_world
    wall = WallReturn(reflector=0, crossing_frame=40, rate_mps=1.5, frames=10)
    frames, truth = synthetic_stream(
        world,
        loop,
        np.random.default_rng(11),
        clutter_per_frame=0.0,
        miss_probability=0.1,
        wall=wall,
    )
    _, _, views = run(world, cfg, frames)

    def follower(k):
        """Confirmed track of type 0 nearest to reflector 0."""
        tracks = [t for t in views[k] if t.type_index == 0 and t.status == "confirmed"]
        return min(tracks, key=lambda t: abs(t.distance_m - truth[k, 0]))

    before, after = follower(33), follower(48)
    assert after.track_id == before.track_id
    assert abs(after.distance_m - truth[48, 0]) < 0.05


def test_reflector_lost_for_three_frames_is_picked_up(two_type_world, loop):
    cfg, world = two_type_world
    first = 50
    frames, truth = synthetic_stream(
        world,
        loop,
        np.random.default_rng(5),
        miss_probability=0.0,
        clutter_per_frame=0.0,
        dropouts={2: (first, 3)},
    )
    tracker = LrpTracker.from_world(world, cfg.tracking)
    ids = {}
    for k, det in enumerate(frames[: first + 4]):
        fp = tracker.update(det, DT)
        track = min(
            (t for t in tracker.tracks if t.type_index == 0),
            key=lambda t: abs(t.distance_m - truth[k, 2]),
        )
        ids[k] = track.track_id
        if first <= k < first + 3:  # coasting: still reported, not fresh, still close
            assert not track.fresh and track.misses == k - first + 1
            assert abs(track.distance_m - truth[k, 2]) < 0.1
            assert len(fp.distances_m[0]) == 2
    k = first + 3
    assert ids[k] == ids[first - 1]
    assert track.fresh and abs(track.distance_m - truth[k, 2]) < 0.05
    assert np.all(fp.fresh[0])


def test_never_more_tracks_than_reflectors(two_type_world, loop):
    cfg, world = two_type_world
    frames, _ = synthetic_stream(world, loop, np.random.default_rng(1), clutter_per_frame=4.0)
    _, fps, views = run(world, cfg, frames)
    counts = world.layout.counts_per_type()
    for fp, v in zip(fps, views, strict=True):
        for t in (0, 1):
            assert len(fp.distances_m[t]) <= counts[t]
            assert sum(x.type_index == t and x.status == "confirmed" for x in v) <= counts[t]
            assert np.all(np.diff(fp.distances_m[t]) >= 0)


def test_deterministic_and_reset(two_type_world, loop):
    cfg, world = two_type_world
    frames, _ = synthetic_stream(world, loop, np.random.default_rng(2))
    tracker = LrpTracker.from_world(world, cfg.tracking)
    first = [tracker.update(d, DT) for d in frames]
    tracker.reset()
    second = [tracker.update(d, DT) for d in frames]
    frames2, _ = synthetic_stream(world, loop, np.random.default_rng(2))
    third = [LrpTracker.from_world(world, cfg.tracking).update(d, DT) for d in frames2[:1]]
    for a, b in zip(first, second, strict=True):
        for t in (0, 1):
            np.testing.assert_array_equal(a.distances_m[t], b.distances_m[t])
            np.testing.assert_array_equal(a.fresh[t], b.fresh[t])
    np.testing.assert_array_equal(first[0].distances_m[0], third[0].distances_m[0])


def test_first_frame_reports_tentative_distances(paper_cfg, paper_world):
    truth = paper_world.true_distances_m(np.array([2.0, 2.0]))
    det = Detections(truth, np.zeros(4), np.zeros(4), np.zeros(4), np.full(4, 20.0))
    tracker = LrpTracker.from_world(paper_world, paper_cfg.tracking)
    fp = tracker.update(det, 0.25)
    np.testing.assert_allclose(fp.distances_m[0], np.sort(truth))
    assert not fp.fresh[0].any()  # not confirmed yet
    m = paper_cfg.tracking.confirm_hits
    for _ in range(m - 1):
        fp = tracker.update(det, 0.25)
    assert fp.fresh[0].all()
    assert all(t.status == "confirmed" for t in tracker.tracks)


def test_isolated_clutter_never_confirms(paper_cfg, paper_world):
    tracker = LrpTracker.from_world(paper_world, paper_cfg.tracking)
    for k in range(50):
        # One reflector-like detection per frame, never twice near the same range.
        r = np.array([3.0 + (0.7 * k) % 3.0])
        det = Detections(r, np.zeros(1), np.zeros(1), np.zeros(1), np.full(1, 20.0))
        tracker.update(det, 0.25)
        assert all(t.status == "tentative" for t in tracker.tracks)


def test_bad_arguments(paper_cfg, paper_world):
    with pytest.raises(ValueError):
        LrpTracker(paper_world.layout, paper_cfg.tracking, max_range_m=1.0, min_range_m=2.0)
    tracker = LrpTracker.from_world(paper_world, paper_cfg.tracking)
    with pytest.raises(ValueError):
        tracker.update(Detections(), 0.0)
    fp = tracker.update(Detections(), 0.25)
    assert fp.count == 0


# ---------------------------------------------------------------- ego motion and map prior
def exact_ego(trajectory):
    """Noise-free odometry and speed of a drive (what the tracker's ego input carries)."""
    from lrp_gym.tracking.range_prediction import EgoMotion
    from lrp_gym.world.robot import odometry_delta

    poses = trajectory.poses
    speed = np.linalg.norm(trajectory.velocities_xy_mps, axis=1)
    odo = [np.zeros(3)] + [odometry_delta(poses[k - 1], poses[k]) for k in range(1, len(poses))]
    return [EgoMotion(float(s), o) for s, o in zip(speed, odo, strict=True)]


def with_extra(frames, extra):
    """Append one detection per frame: extra[k] = (range, velocity, rcs) or None."""
    out = []
    for det, e in zip(frames, extra, strict=True):
        if e is not None:
            det = Detections.concatenate([det, Detections([e[0]], [e[1]], [0.0], [e[2]], [20.0])])
        out.append(det)
    return out


def test_prior_picks_the_reflectors_over_a_static_phantom(two_type_world, loop):
    """A static point that is no reflector, with the best RCS fit: only the prior rejects it."""
    from lrp_gym.tracking.prior import DistancePrior

    cfg, world = two_type_world
    frames, truth = synthetic_stream(world, loop, np.random.default_rng(4), clutter_per_frame=0.0)
    phantom = np.array([2.5, 2.6, 3.0])
    radar = world.radar_position(loop.poses[:, :2])
    diff = radar - phantom
    r = np.linalg.norm(diff, axis=1)
    v = np.einsum("kj,kj->k", diff[:, :2], loop.velocities_xy_mps) / r
    peak_a = world.layout.types[0].rcs_dbsm
    frames = with_extra(frames, [(r[k], v[k], peak_a - 3.0) for k in range(len(frames))])
    ti = world.layout.type_index
    ego = exact_ego(loop)

    def reported_phantom(use_prior):
        tracker = LrpTracker.from_world(world, cfg.tracking)
        hits, errors = 0, []
        for k, det in enumerate(frames):
            xy = loop.poses[k, :2] + np.array([0.03, -0.02])  # an estimate a few cm off
            prior = DistancePrior.from_pose(
                world.layout, world.mount_height_m, xy, np.eye(2) * 0.05**2
            )
            fp = tracker.update(det, DT, ego[k], prior if use_prior else None)
            if k >= 5:
                hits += (
                    bool(np.any(np.abs(fp.distances_m[0] - r[k]) < 0.02))
                    and np.min(np.abs(truth[k, ti == 0] - r[k])) > 0.1
                )
                errors.append(per_type_errors_m(fp.distances_m, truth[k], ti))
        return hits, np.abs(np.concatenate(errors))

    hits_prior, err_prior = reported_phantom(True)
    hits_free, _ = reported_phantom(False)
    assert hits_free > 20  # without the map the phantom looks as good as a reflector
    assert hits_prior == 0
    assert np.percentile(err_prior, 95) < 0.05


def test_ego_motion_rejects_a_wall_approached_head_on(paper_cfg, paper_world):
    """A return closing at the robot's full speed cannot be a reflector above it."""
    from lrp_gym.tracking.range_prediction import EgoMotion

    def confirmed(use_ego):
        tracker = LrpTracker.from_world(paper_world, paper_cfg.tracking)
        n = 0
        for k in range(5):
            r = 4.5 - 0.5 * k  # wall 4.5 m ahead, 2 m/s, 0.25 s frames
            det = Detections([r], [-2.0], [0.0], [0.0], [20.0])
            ego = EgoMotion(2.0, [0.0, 0.5 if k else 0.0, 0.0]) if use_ego else None
            tracker.update(det, 0.25, ego)
            n += sum(t.status != "tentative" for t in tracker.tracks)
        return n

    assert confirmed(False) > 0
    assert confirmed(True) == 0


def test_a_return_moving_with_the_robot_scores_as_no_static_point(paper_cfg, paper_world):
    """The ceiling (constant range, zero Doppler while driving) keeps a high innovation.

    At the paper's 0.5 m between frames; at small steps the one-frame misfit (which grows
    with the square of the step) drowns in the measurement noise.
    """
    traj = path_trajectory([[0.75, 2.0], [4.25, 2.0], [4.25, 4.25]], 2.0, 0.25)
    frames, truth = synthetic_stream(
        paper_world, traj, np.random.default_rng(0), miss_probability=0.0, clutter_per_frame=0.0
    )
    up = paper_world.room.size_m[2] - paper_world.mount_height_m
    frames = with_extra(frames, [(up, 0.0, 0.0)] * len(frames))
    # A vague prior (particles all over the room) keeps the candidate pool; it barely ranks.
    from lrp_gym.tracking.prior import DistancePrior

    grid = np.stack(np.meshgrid(np.linspace(0.3, 4.7, 12), np.linspace(0.3, 4.7, 12)), -1)
    vague = DistancePrior.from_particles(
        paper_world.layout,
        paper_world.mount_height_m,
        grid.reshape(-1, 2),
        np.ones(144),
    )
    tracker = LrpTracker.from_world(paper_world, paper_cfg.tracking)
    for det, ego in zip(frames, exact_ego(traj), strict=True):
        tracker.update(det, 0.25, ego, vague)
    nis = {round(t.distance_m, 1): t.nis for t in tracker.tracks if t.status != "tentative"}
    ceiling = nis.pop(round(up, 1))
    assert len(nis) == 4
    assert ceiling > 2.0 * max(nis.values())


def test_persistent_fingerprint_holds_every_persistent_return(paper_cfg, paper_world):
    """Reflectors plus a steady room return: all persistent, only the reflectors reported."""
    from lrp_gym.tracking.prior import DistancePrior

    traj = path_trajectory([[0.75, 2.0], [4.25, 2.0]], 2.0, 0.25)
    frames, truth = synthetic_stream(
        paper_world, traj, np.random.default_rng(0), miss_probability=0.0, clutter_per_frame=0.0
    )
    up = paper_world.room.size_m[2] - paper_world.mount_height_m
    frames = with_extra(frames, [(up, 0.0, 0.0)] * len(frames))
    tracker = LrpTracker.from_world(paper_world, paper_cfg.tracking)
    for k, (det, ego) in enumerate(zip(frames, exact_ego(traj), strict=True)):
        prior = DistancePrior.from_pose(
            paper_world.layout, paper_world.mount_height_m, traj.poses[k, :2], np.eye(2) * 1e-3
        )
        fp = tracker.update(det, 0.25, ego, prior)
    pool = tracker.persistent_fingerprint()
    assert len(pool.distances_m[0]) == 5 and np.all(pool.fresh[0])
    assert np.min(np.abs(pool.distances_m[0] - up)) < 0.02
    np.testing.assert_allclose(fp.distances_m[0], np.sort(truth[-1]), atol=0.05)
