"""Each perturbation changes what the radar, the odometry or the true pose shows as intended."""

from __future__ import annotations

from dataclasses import replace

import gymnasium as gym
import numpy as np
import pytest

import lrp_gym  # noqa: F401  (registers the env ids)
from lrp_gym.config import PerturbationsConfig, ScenarioError
from lrp_gym.experiments.episodes import perturbed_after_frame, perturbed_reflectors
from lrp_gym.perturbations import NAMES, FrameContext, PerturbationSet
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world import World

POSE = np.array([2.5, 2.0, 0.3])


@pytest.fixture(scope="module")
def quiet(paper_cfg):
    """Noise-free detections-level radar in the paper room: exact, repeatable detections."""
    cfg = paper_cfg.with_overrides({"radar": {"fidelity": "detections", "noise": False}})
    world = World.from_config(cfg)
    return cfg, world, RadarSensor(world, cfg.radar)


def make_set(world, **sections) -> PerturbationSet:
    return PerturbationSet.from_config(PerturbationsConfig.model_validate(sections), world)


def ctx(world, sensor, frame=0, pose=POSE, layout=None):
    return FrameContext(frame, pose, world, layout or world.layout, 0.25, sensor)


def near(det_range_m, target_m, tol=0.06):
    return bool(np.any(np.abs(np.asarray(det_range_m) - target_m) < tol))


def test_registry_matches_schema_and_unknown_names_are_rejected(paper_cfg):
    assert set(NAMES) == set(PerturbationsConfig.model_fields)
    with pytest.raises(ScenarioError) as exc:
        paper_cfg.with_overrides({"perturbations": {"earthquake": {}}})
    assert "unknown perturbation 'earthquake'" in str(exc.value)
    assert "missed_detections" in str(exc.value)
    with pytest.raises(ScenarioError, match="severity"):
        paper_cfg.with_overrides({"perturbations": {"clutter": {"severity": 1.5}}})


def test_static_shadowing_hides_that_reflector_for_exactly_n_frames(quiet):
    cfg, world, sensor = quiet
    ps = make_set(world, shadowing={"frames": 10, "start_frames": [4, 4]})
    rng = np.random.default_rng(0)
    ps.reset(ctx(world, sensor), rng)
    target = int(ps["shadowing"].targets[0])
    masks = [ps.radar_inputs(ctx(world, sensor, k), rng)[0] for k in range(30)]
    hidden_frames = [k for k, m in enumerate(masks) if m is not None and m.any()]
    assert hidden_frames == list(range(4, 14))
    assert all(np.flatnonzero(masks[k]).tolist() == [target] for k in hidden_frames)
    # The monitor's naming budget counts from the frame it disappeared.
    assert perturbed_reflectors(ps) == (target,) and perturbed_after_frame(ps) == (3,)
    # In the channel: every path of that reflector is gone, the others' stay.
    free = sensor.paths(POSE, np.zeros(2))
    shadowed = sensor.paths(POSE, np.zeros(2), hidden=masks[5])
    assert target in free.reflector_index and target not in shadowed.reflector_index
    for j in set(range(4)) - {target}:
        assert np.sum(free.reflector_index == j) == np.sum(shadowed.reflector_index == j) > 0


def test_severity_sets_shadow_duration(quiet):
    _, world, _ = quiet
    assert make_set(world, shadowing={"severity": 0.25})["shadowing"].frames == 10


def test_person_crossing_hides_only_its_reflector_for_about_n_frames(quiet):
    _, world, sensor = quiet
    counts = []
    for seed in range(10):
        ps = make_set(world, shadowing={"mode": "person", "frames": 6, "start_frames": [2, 2]})
        rng = np.random.default_rng(seed)
        ps.reset(ctx(world, sensor), rng)
        target = int(ps["shadowing"].targets[0])
        n = 0
        for k in range(40):
            m = ps.radar_inputs(ctx(world, sensor, k), rng)[0]
            if m is not None and m.any():
                assert np.flatnonzero(m).tolist() == [target]
                assert k >= 2
                n += 1
        counts.append(n)
    # The box width passes the line of sight in ~6 frames; oblique crossings take longer.
    assert min(counts) >= 3 and max(counts) <= 6 * 3 and 4 <= np.median(counts) <= 10


def test_missed_detections_drop_about_p(quiet):
    _, world, sensor = quiet
    ps = make_set(world, missed_detections={"probability": 0.2})
    rng = np.random.default_rng(1)
    det = sensor.measure(POSE, np.zeros(2), rng)
    kept = sum(len(ps.filter_detections(ctx(world, sensor), det, rng)) for _ in range(400))
    total = 400 * len(det)
    frac = 1 - kept / total
    sd = np.sqrt(0.2 * 0.8 / total)
    assert abs(frac - 0.2) < 4 * sd


def test_clutter_adds_detections_at_the_scatterers_ranges(quiet):
    _, world, sensor = quiet
    ps = make_set(world, clutter={"count": 3, "rcs_spread_db": 0.0})
    rng = np.random.default_rng(2)
    ps.reset(ctx(world, sensor), rng)
    c = ps["clutter"]
    assert c.positions_m.shape == (3, 3)
    assert np.allclose(10 * np.log10(c.rcs_m2), world.layout.types[0].rcs_dbsm)
    hidden, extra = ps.radar_inputs(ctx(world, sensor), rng)
    assert hidden is None
    paths = sensor.paths(POSE, np.zeros(2), hidden=hidden, extra_scatterers=extra)
    base = sensor.paths(POSE, np.zeros(2))
    radar = world.radar_position(POSE[:2])
    r = np.linalg.norm(c.positions_m - radar, axis=1)
    clutter = paths.select(paths.reflector_index == -2)
    assert np.allclose(np.sort(clutter.range_m), np.sort(r))
    # Reflector-like: the radar equation with the antenna gains gives the type's RCS back.
    gain = clutter.power_w * (4 * np.pi) ** 3 * clutter.range_m**4 / sensor.link_w_m2
    assert np.all(gain <= world.layout.types[0].rcs_m2 * (1 + 1e-9))
    assert np.all(gain > 0.01 * world.layout.types[0].rcs_m2)
    assert len(paths) == len(base) + 3


def test_displaced_reflector_shifts_the_detected_distance_not_the_map(quiet):
    cfg, world, _ = quiet
    ps = make_set(world, displaced_reflector={"shift_m": 0.5})
    rng = np.random.default_rng(3)
    sensor = RadarSensor(world, cfg.radar)
    layout = ps.reset(ctx(world, sensor), rng)
    moved = ps["displaced_reflector"].moved
    assert len(moved) == 1
    assert perturbed_after_frame(ps) == (0,)  # moved before the episode: budget from frame 0
    shift = layout.positions_m - world.layout.positions_m
    j = int(moved[0])
    assert np.linalg.norm(shift[j, :2]) == pytest.approx(0.5, abs=0.01) or np.any(
        np.isclose(layout.positions_m[j, :2], [0.05, 4.95])  # clipped at a wall
    )
    assert np.all(shift[np.arange(4) != j] == 0) and shift[j, 2] == 0
    assert world.layout.positions_m[j] is not layout.positions_m[j]
    seen = RadarSensor(replace(world, layout=layout), cfg.radar)
    old = world.true_distances_m(POSE[:2])[j]
    new = layout.distances_m(world.radar_position(POSE[:2]))[j]
    assert abs(new - old) > 0.1
    direct = seen.paths(POSE, np.zeros(2))
    direct = direct.select((direct.reflector_index == j) & (direct.order == 0))
    assert direct.range_m == pytest.approx([new])


def test_incidence_angle_removes_returns_at_large_angles(quiet):
    _, world, sensor = quiet
    ps = make_set(world, incidence_angle={"severity": 1.0})
    narrow = ps.reset(ctx(world, sensor), np.random.default_rng(0))
    t = narrow.types[0]
    assert (t.half_angle_deg, t.cutoff_deg) == pytest.approx((10.0, 36.0))
    # Sample the floor: where a reflector's incidence angle exceeds the cutoff it is dark.
    xy = np.stack(np.meshgrid(np.linspace(0.3, 4.7, 12), np.linspace(0.3, 4.7, 12)), -1)
    radar = world.radar_position(xy.reshape(-1, 2))
    to_radar = radar[:, None, :] - world.layout.positions_m
    cos = np.einsum("nmk,mk->nm", to_radar, world.layout.axes) / np.linalg.norm(to_radar, axis=-1)
    angle = np.degrees(np.arccos(cos))
    before, after = world.layout.effective_rcs_m2(radar), narrow.effective_rcs_m2(radar)
    assert np.all(after[angle > 36.0] == 0) and np.all(before[angle < 80.0] > 0)
    assert np.all(after <= before + 1e-15)
    assert (angle > 36.0).any()


def test_interference_adds_bursts_of_reflector_like_detections(quiet):
    _, world, sensor = quiet
    ps = make_set(
        world, interference={"burst_probability": 0.1, "burst_frames": 3, "detections_per_frame": 5}
    )
    rng = np.random.default_rng(4)
    ps.reset(ctx(world, sensor), rng)
    base = sensor.measure(POSE, np.zeros(2), rng)
    extra = [
        len(ps.filter_detections(ctx(world, sensor, k), base, rng)) - len(base) for k in range(600)
    ]
    extra = np.array(extra)
    assert set(extra.tolist()) == {0, 5}
    # Bursts come in runs of 3 frames: every run length is a multiple of 3 (adjacent bursts merge).
    runs = np.diff(np.flatnonzero(np.diff(np.r_[0, extra > 0, 0])))[::2]
    assert np.all(runs % 3 == 0)
    # A burst starts with p = 0.1 per quiet frame: about 600 / (1/0.1 + 3) bursts.
    n_bursts = (extra > 0).sum() / 3
    assert 25 < n_bursts < 70
    spur = ps["interference"].spurious(ctx(world, sensor), rng)
    peak = world.layout.types[0].rcs_dbsm
    assert np.all(np.abs(spur.rcs_dbsm - peak) <= 6.0 + 1e-9)
    assert np.allclose(
        sensor.rcs_dbsm(10 ** ((spur.power_dbm - 30) / 10), spur.range_m), spur.rcs_dbsm
    )


def test_odometry_slip_scales_reported_distance_and_biases_heading(quiet):
    _, world, sensor = quiet
    ps = make_set(world, odometry_slip={"slip": 0.2, "heading_bias_dps": 8.0})
    odo, pose = ps.move(ctx(world, sensor, 1), np.array([0.1, 0.5, -0.1]), np.random.default_rng(0))
    assert pose is None
    bias = np.deg2rad(8.0) * 0.25 / 2
    assert odo == pytest.approx([0.1 + bias, 0.6, -0.1 + bias])


def test_kidnapping_moves_the_true_pose_but_not_the_estimate(paper_cfg):
    over = {
        "localization": {"init": "gaussian", "init_std": [0.05, 0.05, 0.05]},
        "perturbations": {"kidnapping": {"frames": [3, 3], "min_jump_m": 2.0}},
    }
    env = gym.make("LRPRadarNavFast-v0", scenario="ipin2023", overrides=over)
    _, info = env.reset(seed=0)
    poses, est = [info["true_pose"]], [info["est_pose"]]
    for _ in range(4):
        _, _, term, _, info = env.step(np.zeros(2))  # standing still: only the kidnap moves it
        poses.append(info["true_pose"])
        est.append(info["est_pose"])
    assert env.unwrapped.perturbations["kidnapping"].kidnap_frame == 3
    jumps = [np.linalg.norm(b[:2] - a[:2]) for a, b in zip(poses, poses[1:], strict=False)]
    assert jumps[2] >= 2.0 and max(jumps[:2] + jumps[3:]) < 1e-9
    assert np.linalg.norm(est[3][:2] - est[2][:2]) < 0.5  # the localiser was not told
    assert env.unwrapped.world.room.free(poses[3][None, :2], env.unwrapped._radius_m)[0]
    env.close()


def run(env_id, over, seed, steps=25):
    env = gym.make(env_id, scenario="ipin2023", overrides=over)
    obs, info = env.reset(seed=seed)
    out = [obs]
    for k in range(steps):
        obs, r, term, trunc, info = env.step(np.array([0.6, 0.3 * np.sin(k)]))
        out.append(np.r_[obs, r, info["true_pose"], info["n_detections"]])
        if term:
            break
    env.close()
    return out


ALL = {n: {"severity": 0.5} for n in NAMES if n != "kidnapping"} | {
    "kidnapping": {"frames": [4, 6]}
}


def test_perturbed_episodes_are_deterministic_per_seed():
    a = run("LRPRadarNavFast-v0", {"perturbations": ALL}, 7)
    b = run("LRPRadarNavFast-v0", {"perturbations": ALL}, 7)
    c = run("LRPRadarNavFast-v0", {"perturbations": ALL}, 8)
    assert len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert not all(np.array_equal(x, y) for x, y in zip(a, c, strict=False))


def test_no_perturbation_means_no_hook():
    env = gym.make("LRPRadarNavFast-v0")
    assert env.unwrapped.perturbations is None
    env.close()


def test_the_same_seed_perturbs_and_senses_the_same_way_whatever_the_localiser_draws():
    """Two localiser settings that draw different numbers of values (10 000 or 500 initial
    particles) on one seed: the same clutter scatterers, the same kidnap frame and put-down
    (the true poses under the same actions) and the same radar detections and odometry in
    every frame, because the perturbations and the sensing draw from their own children of
    the robot's generator."""
    import gymnasium as gym

    runs = []
    for particles in (10_000, 500):
        over = {
            "radar": {"fidelity": "detections"},
            "perturbations": {
                "clutter": {"severity": 0.5},
                "kidnapping": {"severity": 1.0, "frames": [3, 3]},
            },
            "localization": {"initial_particles": particles},
        }
        env = gym.make("LRPRadarNavFast-v0", overrides=over)
        env.reset(seed=11)
        pert = env.unwrapped.core.perturbations[0]
        scatterers = pert["clutter"].positions_m.copy()
        core = env.unwrapped.core
        poses, ranges, odometry = [], [core.frames[0].detections.range_m], []
        stack_step = core.stacks[0].step

        def spy(pose, velocity_xy, odo, *args, seen=odometry, step=stack_step, **kwargs):
            seen.append(np.array(odo))  # the noisy odometry the stack is given
            return step(pose, velocity_xy, odo, *args, **kwargs)

        core.stacks[0].step = spy
        for _ in range(6):
            *_, info = env.step(np.array([0.0, 0.5]))  # turn on the spot: never collides
            poses.append(info["true_pose"])
            ranges.append(core.frames[0].detections.range_m)
        sensed = (np.concatenate(ranges), np.array(odometry))
        runs.append((scatterers, np.array(poses), pert["kidnapping"].kidnap_frame, sensed))
        env.close()
    (s1, p1, k1, sensed1), (s2, p2, k2, sensed2) = runs
    assert len(s1) > 0
    np.testing.assert_array_equal(s1, s2)
    assert k1 == k2 == 3
    assert np.linalg.norm(p1[2, :2] - p1[1, :2]) > 2.0  # the put-down happened
    np.testing.assert_array_equal(p1, p2)
    assert len(sensed1[0]) > 0
    for a, b in zip(sensed1, sensed2):
        np.testing.assert_array_equal(a, b)
