"""AMCL recovery (Augmented MCL on the distance fit) and the ``converged`` flag.

The trajectory is a 1.4 m-radius loop around the centre of the paper's 5 m room, one frame
per 0.5 m. The layout is an asymmetric one (the paper scenario's at the time of writing,
pinned here): with a nearly symmetric layout a loop around its centre has a mirror loop with
almost the same fingerprints, and no filter could tell a kidnap from normal driving.
"""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.config import load_scenario
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.localization.particle_statistics import dominant_cluster
from lrp_gym.localization.proposal import LostTest, MeasurementGrid
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world import World
from lrp_gym.world.robot import odometry_delta

ASYMMETRIC = [
    {"position": [4.588, 4.648, 3.0], "type": "A"},
    {"position": [0.583, 2.928, 3.0], "type": "A"},
    {"position": [0.351, 0.712, 3.0], "type": "A"},
    {"position": [0.958, 4.621, 3.0], "type": "A"},
]
RADIUS_M, STEP_M = 1.4, 0.5
KIDNAP_FRAME = 20


@pytest.fixture(scope="module")
def room():
    cfg = load_scenario("ipin2023").with_overrides({"reflectors": {"layout": ASYMMETRIC}})
    return World.from_config(cfg), cfg.localization


def _pose(phi: float) -> np.ndarray:
    return np.array([2.5 + RADIUS_M * np.cos(phi), 2.5 + RADIUS_M * np.sin(phi), phi + np.pi / 2])


def _fingerprint(world, pose):
    return Fingerprint.from_true(world.layout, world.radar_position(pose[:2]))


def _corrupt(fp: Fingerprint, rng: np.random.Generator, p_miss: float, p_clutter: float):
    """Distance noise (3 cm), a missed reflector, a clutter distance, or only two distances."""
    d = fp.distances_m[0]
    if rng.random() < 0.1:
        d = np.delete(d, rng.choice(len(d), 2, replace=False))
    elif rng.random() < p_miss:
        d = np.delete(d, rng.integers(len(d)))
    if rng.random() < p_clutter:
        d = np.r_[d, rng.uniform(0.5, 6.0)]
    return Fingerprint.from_distances(("A",), [np.abs(d + rng.normal(0.0, 0.03, len(d)))])


def _drive(world, loc, seed, frames, kidnap=False, corrupt=None):
    """Errors (frames,) and injected particle counts (frames,) along the loop."""
    rng = np.random.default_rng(seed)
    amcl = Amcl(world, loc)
    amcl.reset(rng)
    phi = rng.uniform(0.0, 2.0 * np.pi)
    errors, injected = np.zeros(frames), np.zeros(frames, dtype=int)
    for k in range(frames):
        step = STEP_M / RADIUS_M
        odo = odometry_delta(_pose(phi), _pose(phi + step))
        phi += step
        if kidnap and k == KIDNAP_FRAME:  # >= 1.5 m chord away; the filter is not told
            phi += rng.uniform(np.deg2rad(70.0), np.deg2rad(290.0))
        pose = _pose(phi)
        odo = world.odometry_noise.sample(odo, (), rng) if k else np.zeros(3)
        fp = _fingerprint(world, pose)
        if corrupt is not None and k >= 8:
            fp = _corrupt(fp, rng, *corrupt)
        est = amcl.update(odo, fp, rng)
        errors[k] = np.hypot(*(est.pose[:2] - pose[:2]))
        injected[k] = amcl.n_injected
    return errors, injected


def test_kidnap_jump_is_at_least_1_5_m():
    chord = 2.0 * RADIUS_M * np.sin(np.deg2rad(70.0) / 2.0)
    assert chord >= 1.5


def test_recovers_from_kidnapping_within_15_frames(room):
    world, loc = room
    recovered = []
    for seed in range(20):
        errors, _ = _drive(world, loc, seed, KIDNAP_FRAME + 20, kidnap=True)
        assert errors[KIDNAP_FRAME - 5 : KIDNAP_FRAME].max() < 0.2  # converged before
        assert errors[KIDNAP_FRAME] > 1.0  # the kidnap is real
        after = errors[KIDNAP_FRAME:]
        # Back under 0.2 m within 15 frames and staying there to the end of the run.
        recovered.append(np.all(after[15:] < 0.2) and np.any(after[:16] < 0.2))
    assert np.mean(recovered) >= 0.9, recovered


def test_without_recovery_the_kidnap_is_not_recovered(room):
    """The same runs with the averages frozen (alpha 0): the filter stays lost, so the test
    above measures the recovery and not the filter's ordinary tracking."""
    world, loc = room
    off = loc.model_copy(
        update={
            "alpha_slow": 0.0,
            "alpha_fast": 0.0,
            "global_proposal": False,
            "mode_min_particles": 0,
            "likelihood_exponent": 1.0,
        }
    )
    lost = [_drive(world, off, s, KIDNAP_FRAME + 16, kidnap=True)[0][-1] > 0.2 for s in range(6)]
    assert np.mean(lost) >= 0.5


@pytest.mark.parametrize("corrupt", [(0.5, 0.5), (1.0, 1.0)], ids=["mixed", "miss+clutter"])
def test_converged_filter_on_normal_data_injects_almost_nothing(room, corrupt):
    world, loc = room
    off = loc.model_copy(update={"alpha_slow": 0.0, "alpha_fast": 0.0, "global_proposal": False})
    err_on, err_off, injected, updates = [], [], 0, 0
    for seed in range(8):
        e_on, inj = _drive(world, loc, 100 + seed, 50, corrupt=corrupt)
        e_off, _ = _drive(world, off, 100 + seed, 50, corrupt=corrupt)
        err_on.append(e_on[10:])
        err_off.append(e_off[10:])
        injected += int(inj[10:].sum())
        updates += 40
    # Under 1 % of one converged particle set (~1000) per update on average...
    assert injected / updates < 10.0, injected
    # ...and no loss of accuracy against the same runs without recovery.
    assert np.mean(err_on) <= 1.05 * np.mean(err_off) + 0.005
    assert np.quantile(err_on, 0.95) <= 1.1 * np.quantile(err_off, 0.95) + 0.01


def test_averages_start_at_the_first_fit(room):
    world, loc = room
    rng = np.random.default_rng(0)
    amcl = Amcl(world, loc)
    amcl.reset(rng, _pose(0.0))
    assert amcl.w_slow == amcl.w_fast == 0.0
    amcl.update(np.zeros(3), _fingerprint(world, _pose(0.0)), rng)
    assert amcl.w_slow == amcl.w_fast > 0.0
    assert amcl.p_random == 0.0


# --------------------------------------------------------------------------- distance fit
def test_distance_fits_exact_clutter_and_truncation(room):
    world, _ = room
    model = FingerprintModel(world.layout, world.mount_height_m, 0.075, 0.2, 20.0)
    xy = np.array([[1.5, 2.0]])
    d = _fingerprint(world, np.array([1.5, 2.0, 0.0])).distances_m[0]
    exact = model.distance_fits(xy, np.ones(1), Fingerprint.from_distances(("A",), [d]))
    np.testing.assert_allclose(exact, 1.0, atol=1e-5)
    assert np.min(np.diff(d)) > 0.2  # so that the nearest expected distance is its own
    s2 = 0.075**2 + 0.075**2  # model variance + the fingerprint's reported variance
    shifted = Fingerprint.from_distances(("A",), [d + 0.05])
    np.testing.assert_allclose(
        model.distance_fits(xy, np.ones(1), shifted), np.exp(-(0.05**2) / (2 * s2)), 1e-4
    )
    # Two clutter distances far from every reflector: 6 measured, only the 4 best kept.
    extra = Fingerprint.from_distances(("A",), [np.r_[d, 9.0, 9.5]])
    fits = model.distance_fits(xy, np.ones(1), extra)
    assert len(fits) == 4 and np.all(fits > 0.99)
    one_bad = model.distance_fits(xy, np.ones(1), Fingerprint.from_distances(("A",), [[9.0]]))
    assert one_bad[0] < 1e-6
    assert len(model.distance_fits(xy, np.ones(1), Fingerprint.from_distances(("B",), [d]))) == 0


def test_distance_fits_are_weighted_means(room):
    world, _ = room
    model = FingerprintModel(world.layout, world.mount_height_m, 0.075, 0.2, 20.0)
    xy = np.array([[2.0, 1.5], [4.0, 4.0]])
    fp = Fingerprint.from_distances(("A",), [_fingerprint(world, np.r_[xy[0], 0.0]).distances_m[0]])
    each = [model.distance_fits(xy[i : i + 1], np.ones(1), fp) for i in range(2)]
    both = model.distance_fits(xy, np.array([3.0, 1.0]), fp)
    # The returned fits are sorted per type; compare the sums (order-free).
    assert np.sum(both) == pytest.approx(0.75 * np.sum(each[0]) + 0.25 * np.sum(each[1]), 1e-5)


# --------------------------------------------------------------------------- converged
def _set(amcl, particles, weights=None):
    amcl.particles = particles
    amcl.weights = np.full(len(particles), 1.0 / len(particles)) if weights is None else weights
    return amcl.estimate()


def test_converged_means_one_tight_mode(room):
    world, loc = room
    rng = np.random.default_rng(3)
    amcl = Amcl(world, loc)
    blob = np.array([2.0, 2.0, 0.0]) + rng.normal(0.0, [0.07, 0.07, 0.1], (2000, 3))
    assert _set(amcl, blob).converged  # sqrt(trace) 0.1 m, one mode
    # A sprinkle of uniformly drawn particles (as injected by the recovery) leaves it
    # settled, although it inflates the whole-set spread far beyond the threshold; the
    # reported claim (converged_mass 0.99) holds with a sprinkle of 0.5 %, not of 5 %.
    stray = amcl.uniform_particles(100, rng)
    est = _set(amcl, np.vstack([blob, stray]))
    assert est.settled and est.position_std_m > loc.converged_std_m
    assert not est.converged and loc.converged_mass > est.confidence
    assert _set(amcl, np.vstack([blob, stray[:10]])).converged
    # Two equally heavy modes 2 m apart: not converged, whatever each one's spread.
    other = blob + np.array([2.0, 0.5, 0.0])
    assert not _set(amcl, np.vstack([blob, other])).converged
    # One mode, but wide.
    wide = np.array([2.5, 2.5, 0.0]) + rng.normal(0.0, [0.4, 0.4, 0.1], (2000, 3))
    assert not _set(amcl, wide).converged
    # The uniform prior.
    assert not _set(amcl, amcl.uniform_particles(5000, rng)).converged


def test_dominant_cluster_mass_and_mask():
    rng = np.random.default_rng(0)
    a = np.column_stack([rng.normal(1.0, 0.05, (300, 2)), np.zeros(300)])
    b = np.column_stack([rng.normal(3.5, 0.05, (100, 2)), np.zeros(100)])
    w = np.r_[np.full(300, 3.0), np.full(100, 1.0)]
    sel, mass = dominant_cluster(np.vstack([a, b]), w, 0.1, np.array([5.0, 5.0]))
    assert mass == pytest.approx(900.0 / 1000.0)
    assert sel[:300].all() and not sel[300:].any()
    _, flat = dominant_cluster(np.vstack([a, b]), np.zeros(400), 0.1, np.array([5.0, 5.0]))
    assert flat == 0.0


def test_recovery_scored_later_on_another_fingerprint_equals_in_update(room):
    """update(recovery=False) + update_recovery(fp) is update(fp)'s statistic, deferred."""
    world, loc = room
    loc = loc.model_copy(
        update={"initial_particles": 500, "max_particles": 500, "global_proposal": False}
    )
    pose = _pose(0.3)
    fp = Fingerprint.from_true(world.layout, world.radar_position(pose[:2]), 0.05)
    odo = np.array([0.0, 0.5, 0.1])
    stats = []
    for deferred in (False, True):
        amcl = Amcl(world, loc)
        rng = np.random.default_rng(0)
        amcl.reset(rng, pose)
        for _ in range(3):
            amcl.update(odo, fp, rng, recovery=not deferred)
            if deferred:
                before = (amcl.w_fast, amcl.w_slow)
                amcl.update_recovery(fp)
                assert (amcl.w_fast, amcl.w_slow) != before  # the deferred call scored it
        stats.append((amcl.w_fast, amcl.w_slow, amcl.p_random))
    np.testing.assert_allclose(stats[0], stats[1])


def test_lost_test_schedule_skips_only_quiet_frames():
    """``lost_test_every``: a frame skips the test only while quiet, with the statistic at 0
    and the cloud's marginal close to the last best cell, and at most k - 1 frames in a row."""
    test = LostTest(drift_nats=4.0, every_frames=3)
    assert test.due(True, -10.0) is True  # no grid evaluated yet
    test.update_marginal(-10.0, -10.5, 0)  # deficit 0.5 < drift: the statistic stays 0
    assert test.statistic_nats == 0.0
    assert [test.due(True, -10.5) for _ in range(6)] == [False, False, True] * 2
    assert test.due(False, -10.5) is True  # not quiet: the test runs and the count restarts
    assert test.due(True, -10.5) is False
    assert test.due(True, -10.0 - 4.0 + 1.0) is True  # within the margin of the drift: runs
    assert test.due(True, -30.0) is True  # the cloud's likelihood drops (a kidnap): runs
    assert test.due(True, None) is True
    test.statistic_nats = 1.0  # evidence building up: every frame
    assert all(test.due(True, -10.5) for _ in range(4))
    every = LostTest(every_frames=1)
    every.update_marginal(-10.0, -10.5, 0)
    assert all(every.due(True, -10.5) for _ in range(4))


def test_kidnap_recovery_with_the_lost_test_every_8_frames(room, monkeypatch):
    """With the grid skipped on quiet frames the filter evaluates it less often and still
    recovers from the kidnaps of :func:`test_recovers_from_kidnapping_within_15_frames`."""
    world, loc = room
    calls = []
    grid_ll = MeasurementGrid.log_likelihood
    monkeypatch.setattr(
        MeasurementGrid, "log_likelihood", lambda g, *a: calls.append(1) or grid_ll(g, *a)
    )
    sparse = loc.model_copy(update={"lost_test_every": 8})
    recovered, frames = [], 0
    for seed in range(10):
        errors, _ = _drive(world, sparse, seed, KIDNAP_FRAME + 20, kidnap=True)
        after = errors[KIDNAP_FRAME:]
        recovered.append(np.all(after[15:] < 0.2) and np.any(after[:16] < 0.2))
        frames += len(errors)
    assert np.mean(recovered) >= 0.9, recovered
    assert len(calls) < 0.6 * frames  # (every frame: at least one call per frame)


def _wrong_frames_after_kidnap(seed: int, overrides: dict) -> tuple[int, int]:
    """After a >= 3 m kidnap (patrol, pure pursuit, detections fidelity): the frames the
    estimate stays settled more than 0.3 m off from the kidnap on (on the old pose, before
    the lost test notices), and all settled frames more than 0.3 m off within 15 frames
    (a restart may also settle on a wrong mode for a while). Settled, not converged: the
    filter's own flag (0.9) shows the lost test's delay; the reported one (0.99) hides it."""
    from agents.registry import make_agent
    from lrp_gym.config import deep_merge
    from lrp_gym.experiments.episodes import make_eval_env
    from lrp_gym.experiments.robustness import cell_overrides

    over = deep_merge(cell_overrides("kidnapping", 1.0), overrides)
    env = make_eval_env("pure-pursuit", "LRPRadarNavFast-v0", "ipin2023-patrol", overrides=over)
    policy = make_agent("pure-pursuit", env)
    policy.reset()
    obs, _ = env.reset(seed=seed)
    base, kidnap, flags = env.unwrapped, None, []
    for t in range(base.cfg.task.max_episode_steps):
        obs, _, terminated, truncated, info = env.step(policy.act(obs))
        if kidnap is None and base.perturbations["kidnapping"].kidnap_frame is not None:
            kidnap = t
        if kidnap is not None:
            flags.append(bool(base.estimate.settled and info["position_error_m"] > 0.3))
            if t - kidnap >= 14:
                break
        if terminated or truncated:
            break
    unnoticed = next((k for k, wrong in enumerate(flags) if not wrong), len(flags))
    return unnoticed, sum(flags)


def test_a_kidnap_is_noticed_within_a_frame_with_the_tests_own_outlier_class():
    # The weights' clutter probability 0.5 shrinks a lost cloud's deficit per frame towards
    # the lost test's drift: weighed with it, the estimate stays converged on the old pose for
    # longer. On patrol seeds 0-29 (session 15, range std 0.03): with the test's own 0.2 one
    # frame in all (seed 23); with the heavy class 5 frames on seeds 7, 12, 13, 23. (At the
    # earlier range std of 0.075 the heavy class cost 20 frames, up to 3 on seed 12.) Session
    # 27 (the perturbations' own draws, ghost weights): seeds 0-29 own 4 frames in all, at most
    # 1 per kidnap; heavy 6 (one frame more on seeds 2 and 24). Session 28 (the sensing's own
    # draws): own 0 frames on all 30 seeds, heavy 1 (seed 10).
    seeds = (10, 11, 12, 13)
    own = [_wrong_frames_after_kidnap(s, {})[0] for s in seeds]
    assert max(own) <= 1, own
    heavy = {"localization": {"lost_test_clutter_probability": None}}
    assert sum(own) < sum(_wrong_frames_after_kidnap(s, heavy)[0] for s in seeds), own


def test_the_lost_test_follows_the_map_without_suspects(room):
    # The stack swaps in a map without the suspected reflectors; the lost test must weigh
    # with that map too, at its own outlier class, and keep one copy (the grids cache per model).
    from lrp_gym.localization.reflector_monitor import model_without

    world, cfg = room
    amcl = Amcl(world, cfg)
    assert amcl.lost_model.clutter_probability == cfg.lost_test_clutter_probability
    assert amcl.lost_model is amcl.lost_model
    amcl.model = model_without(world, cfg, (1,))
    assert amcl.lost_model.counts == amcl.model.counts != (len(world.layout),)
    assert amcl.lost_model.clutter_probability == cfg.lost_test_clutter_probability
    assert amcl.model.clutter_probability == cfg.clutter_probability


def test_start_grid_spacing_is_its_own_setting(room):
    """``start_grid_m``: None is today's start grid (half the lost test's spacing, the same
    cells); a value changes the start grid only, and the start still finds the robot."""
    world, loc = room
    assert loc.start_grid_m is None and loc.start_cell_m == loc.global_grid_m / 2.0
    default = Amcl(world, loc)
    same = MeasurementGrid(default._size_xy, loc.global_grid_m / 2.0, default._free, 160_000)
    np.testing.assert_array_equal(default.start_grid.centres_m, same.centres_m)
    coarse_cfg = load_scenario("ipin2023").with_overrides(
        {"reflectors": {"layout": ASYMMETRIC}, "localization": {"start_grid_m": 0.1}}
    )
    coarse = Amcl(world, coarse_cfg.localization)
    np.testing.assert_array_equal(coarse.grid.centres_m, default.grid.centres_m)
    np.testing.assert_allclose(coarse.start_grid.cell_xy_m, default.grid.cell_xy_m)
    assert len(coarse.start_grid) == len(default.grid) < len(default.start_grid)
    for seed in range(3):
        errors, _ = _drive(world, coarse_cfg.localization, seed, 12)
        assert errors[-4:].max() < 0.2, errors
    with pytest.raises(ValueError, match="start_grid_m"):
        load_scenario("ipin2023").with_overrides({"localization": {"start_grid_m": 0.0}})
