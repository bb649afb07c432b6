"""The reflector monitor names a moved or missing reflector and nothing else."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import lrp_gym  # noqa: F401  (registers the envs)
from agents.pure_pursuit import PurePursuitPolicy
from lrp_gym.config import ReflectorMonitorConfig, load_scenario
from lrp_gym.localization.monitor_frame import MonitorFrame, masked_by_stronger
from lrp_gym.localization.pose_estimate import PoseEstimate
from lrp_gym.localization.reflector_monitor import ReflectorMonitor
from lrp_gym.radar.detections import Detections
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world import World

CFG = ReflectorMonitorConfig()


@pytest.fixture(scope="module")
def world():
    return World.from_config(load_scenario("ipin2023"))


def _estimate(xy, settled=True):
    """A tight estimate at ``xy``; the monitor learns on ``settled`` frames only."""
    pose, cov = np.array([*xy, 0.0]), np.eye(3) * 1e-4
    return PoseEstimate(pose, cov, 500, 400.0, settled, float(settled), 1, settled)


def _gated(world, xy, drop=()):
    """This frame's reflector-window distances: every reflector's true distance but ``drop``."""
    d = world.layout.distances_m(world.radar_position(np.asarray(xy)))
    keep = np.setdiff1d(np.arange(len(d)), drop)
    return Fingerprint.from_distances(world.layout.type_names, [d[keep]], 0.03)


def _visible_xy(world, monitor, rng, min_gap_m=0.0):
    """A free position from which every reflector counts (visible and resolvable), their
    distances at least ``min_gap_m`` apart."""
    min_gap_m = max(min_gap_m, 2 * world.fmcw.range_resolution_m)
    for _ in range(1000):
        xy = rng.uniform(0.5, 1.0, 2) * world.room.size_m[:2] * 0.9
        d = world.layout.distances_m(world.radar_position(xy))
        gap = np.abs(d[:, None] - d[None, :]) + np.eye(len(d)) * 9
        if monitor.visible(xy).all() and gap.min() >= min_gap_m:
            return xy
    raise AssertionError("no position sees every reflector")


def test_a_reflector_that_stops_answering_is_named_and_cleared_when_it_returns(world):
    mon = ReflectorMonitor(world, CFG, max_range_m=20.0)
    rng = np.random.default_rng(0)
    xy = _visible_xy(world, mon, rng)
    for _ in range(30):
        assert not mon.update(_estimate(xy), _gated(world, xy))
    assert mon.suspects == ()
    changed_at = None
    for k in range(CFG.window_frames):
        if mon.update(_estimate(xy), _gated(world, xy, drop=[2])):
            changed_at = k + 1
            break
    assert mon.suspects == (2,)
    # Named as soon as its miss share passes the threshold (EWMA over ~window_frames).
    assert changed_at is not None and changed_at <= 12
    for _ in range(3 * CFG.window_frames):
        mon.update(_estimate(xy), _gated(world, xy))
    assert mon.suspects == ()
    mon.update(_estimate(xy), _gated(world, xy, drop=[2]))
    mon.reset()
    assert mon.suspects == () and not mon.visible_frames.any()


@pytest.mark.parametrize(
    "cfg",
    [CFG, ReflectorMonitorConfig(bias_m=0.04, displacement_chi2=None)],
    ids=["displacement test", "bias test"],
)
def test_a_reflector_that_answers_always_a_little_too_far_is_named(world, cfg):
    """Moved by about one gate: most of its returns still pass the gate, all on one side."""
    mon = ReflectorMonitor(world, cfg, max_range_m=20.0)
    xy = _visible_xy(world, mon, np.random.default_rng(2))
    d = world.layout.distances_m(world.radar_position(xy))
    shifted = d.copy()
    shifted[1] += 0.06  # inside the 0.105 m gate: no miss, but a bias above bias_m
    fp = Fingerprint.from_distances(world.layout.type_names, [shifted], 0.03)
    for _ in range(cfg.min_visible_frames + 2):
        mon.update(_estimate(xy), fp)
    assert mon.miss_share.max() == 0.0
    assert mon.suspects == (1,)


def _drops(world, mon, seed, rates, frames):
    """Run ``frames`` frames from one position, reflector j missing with probability
    ``rates[j]`` each frame (independently); returns the suspects of every frame.

    The reflectors' distances are kept more than twice the gate apart: there a missing
    reflector's nearest return would be a neighbour's, on one side, and the bias test (not
    under test here) would name it.
    """
    rng = np.random.default_rng(seed)
    xy = _visible_xy(world, mon, rng, min_gap_m=2.5 * CFG.gate_sigmas * CFG.range_std_m)
    named = []
    for _ in range(frames):
        drop = np.flatnonzero(rng.random(len(rates)) < rates)
        mon.update(_estimate(xy), _gated(world, xy, drop=drop))
        named.append(mon.suspects)
    return named


@pytest.mark.parametrize("rate", [0.2, 0.5])
def test_a_miss_rate_common_to_every_reflector_names_none(world, rate):
    """Dropped detections hit all reflectors alike: each one's miss share is the drop rate,
    above suspect_share, but no higher than its peers'. A patrol episode's length, 10 runs."""
    for seed in range(10):
        mon = ReflectorMonitor(world, CFG, max_range_m=20.0)
        named = _drops(world, mon, seed, np.full(4, rate), frames=300)
        assert set().union(*named) == set(), (seed, mon.miss_share, mon.common_share)
        if rate > CFG.suspect_share:  # a miss share alone would name every one
            assert mon.miss_share.min() > CFG.suspect_share


def test_a_reflector_that_never_answers_is_named_while_its_peers_do(world):
    for seed in range(5):
        mon = ReflectorMonitor(world, CFG, max_range_m=20.0)
        named = _drops(world, mon, seed, np.array([0.0, 0.0, 1.0, 0.0]), frames=40)
        assert named[CFG.min_visible_frames - 1] == (2,)  # as soon as it may be judged
        assert set().union(*named) == {2}


def test_a_reflector_that_never_answers_is_named_among_peers_missing_half_the_frames(world):
    for seed in range(5):
        mon = ReflectorMonitor(world, CFG, max_range_m=20.0)
        named = _drops(world, mon, seed, np.array([0.5, 0.5, 1.0, 0.5]), frames=40)
        assert named[-1] == (2,) and set().union(*named) == {2}, seed


def test_a_reflector_missing_far_more_often_than_its_peers_is_named(world):
    """0.9 against a common 0.5: its own miss share (the frames its peers answer in) is 0.8."""
    for seed in range(5):
        mon = ReflectorMonitor(world, CFG, max_range_m=20.0)
        named = _drops(world, mon, seed, np.array([0.5, 0.5, 0.9, 0.5]), frames=60)
        assert named[-1] == (2,) and set().union(*named) == {2}, seed


def test_the_common_share_leaves_out_suspects_and_frames_without_peers(world):
    mon = ReflectorMonitor(world, CFG, max_range_m=20.0)
    n = len(world.layout)
    mon.suspect[3] = True
    seen = np.ones(n, dtype=bool)
    residual = np.array([0.0, np.inf, 0.0, np.inf])  # 1 and the suspect 3 miss
    mon.accumulate(MonitorFrame(seen, residual))
    # 0's peers are 1 and 2 (not the suspect 3): one of two missed; 1's peers 0 and 2: none.
    np.testing.assert_allclose(mon.common_share, [0.5, 0.0, 0.5, 1 / 3])
    # Alone in its frames, a reflector's own miss stands in for the common one: no evidence
    # either way, so it is not named on misses (its bias still counts).
    mon = ReflectorMonitor(world, CFG, max_range_m=20.0)
    alone = np.array([True, False, False, False])
    for _ in range(3 * CFG.min_visible_frames):
        mon.accumulate(MonitorFrame(alone, np.full(n, np.inf)))
    assert mon.miss_share[0] == mon.common_share[0] == 1.0
    assert mon.null_var[0] == 0.0 and mon.suspects == ()


def test_frames_without_a_settled_estimate_are_not_judged(world):
    mon = ReflectorMonitor(world, CFG, max_range_m=20.0)
    xy = _visible_xy(world, mon, np.random.default_rng(1))
    for _ in range(50):
        mon.update(_estimate(xy, settled=False), _gated(world, xy, drop=[0, 1, 2, 3]))
    assert mon.suspects == () and not mon.visible_frames.any()
    # Settled (confidence 0.95) but short of the reported claim (converged_mass 0.99): judged.
    pose, cov = np.array([*xy, 0.0]), np.eye(3) * 1e-4
    settled = PoseEstimate(pose, cov, 500, 400.0, False, 0.95, 1, True)
    mon.update(settled, _gated(world, xy))
    assert mon.visible_frames.any()


def test_out_of_range_reflectors_are_not_expected(world):
    mon = ReflectorMonitor(world, CFG, max_range_m=0.5)
    xy = np.asarray(world.room.size_m[:2]) / 2
    assert not mon.visible(xy).any()
    for _ in range(40):
        mon.update(_estimate(xy), _gated(world, xy, drop=[0, 1, 2, 3]))
    assert mon.suspects == ()


def test_hysteresis_is_validated():
    with pytest.raises(ValueError, match="clear_share"):
        ReflectorMonitorConfig(suspect_share=0.2, clear_share=0.3)


def _patrol(overrides, seed, frames=40, scenario="ipin2023-patrol"):
    env = gym.make("LRPRadarNavFast-v0", scenario=scenario, overrides=overrides)
    policy = PurePursuitPolicy.from_env(env)
    obs, _ = env.reset(seed=seed)
    named = {}
    for t in range(1, frames + 1):
        obs, _, terminated, truncated, info = env.step(policy.act(obs))
        for j in info["suspect_reflectors"]:
            named.setdefault(j, t)
        if terminated or truncated:
            break
    return env.unwrapped, named


def _displaced_patrols(
    shift_m: float, seeds=range(6), scenario="ipin2023-patrol"
) -> tuple[int, int]:
    """Over patrols with one reflector moved by ``shift_m``: episodes naming it within 40
    frames, and episodes naming another one."""
    over = {"perturbations": {"displaced_reflector": {"severity": shift_m}}}
    hits = others = 0
    for seed in seeds:
        env, named = _patrol(over, seed, scenario=scenario)
        moved = set(env.perturbations["displaced_reflector"].moved.tolist())
        hits += bool(moved & set(named))
        others += bool(set(named) - moved)
        if set(named) == moved:
            # The localiser weighs the three others only.
            assert sum(env.localizer.model.counts) == len(env.world.layout) - 1
    return hits, others


def test_a_moved_reflector_is_named_on_the_patrol_and_left_out_of_the_map():
    hits, others = _displaced_patrols(0.5)
    assert hits >= 4
    # Until the moved one is named it pulls the estimate, and another reflector may miss its
    # gate for a while (measured: in about 5 % of the episodes of the 20-episode cells).
    assert others <= 1


@pytest.mark.parametrize("scenario", ["ipin2023-patrol", "ipin2023-2types-patrol"])
def test_a_quarter_metre_move_is_named_on_the_patrol(scenario):
    # A 0.25 m move is often across the lines of sight: it rarely leaves the 0.1 m gate, so
    # the miss count alone names it late or never; the displacement test adds up the frames.
    # Replayed on 30 recorded patrols: named in 29 / 28 (1-type / 2 + 2), by the parity test
    # on the nearest returns in 26 / 20 (docs/robustness.md).
    hits, others = _displaced_patrols(0.25, range(10), scenario)
    assert hits >= 9
    assert others <= 1


def test_a_vanished_reflector_is_named():
    over = {
        "perturbations": {"shadowing": {"mode": "static", "frames": 1000, "start_frames": [1, 1]}}
    }
    env, named = _patrol(over, seed=0)
    assert set(named) == set(env.perturbations["shadowing"].targets.tolist())


def test_nothing_is_named_in_the_surveyed_room():
    # The null rate: a few centimetres of pose error can leave one reflector's residual
    # one-sided for a while (measured: 1 of 30 clean 1-type patrols, 0 of 30 on 2 + 2).
    named_episodes = 0
    for seed in range(6):
        env, named = _patrol({}, seed, frames=80)
        named_episodes += bool(named)
        if not named:
            assert sum(env.localizer.model.counts) == len(env.world.layout)
    assert named_episodes <= 1


def _detections(range_m, rcs_dbsm):
    r = np.asarray(range_m, dtype=float)
    zero = np.zeros(len(r))
    return Detections(r, zero, zero, np.asarray(rcs_dbsm, dtype=float), zero)


def test_only_a_much_stronger_return_near_its_distance_masks_a_reflector():
    predicted = np.array([3.0, 4.0, 5.0, 6.0])
    expected = np.zeros(4)  # 0 dBsm each
    # 12 dB stronger 0.2 m away from reflector 0; 12 dB stronger but within the gate of 1 (its
    # own return, or one answering for it); 5 dB stronger 0.2 m from 2; 12 dB, 0.5 m from 3.
    det = _detections([3.2, 4.05, 5.2, 6.5], [12.0, 12.0, 5.0, 12.0])
    masked = masked_by_stronger(predicted, expected, det, 0.105, 0.3, 10.0)
    assert masked.tolist() == [True, False, False, False]


def test_a_reflector_masked_by_a_strong_scatterer_is_not_named_for_its_misses(world):
    # A strong scatterer 0.2 m beyond reflector 2's distance, and reflector 2 unseen in every
    # frame: masked, the frames say nothing of it; without the masking rule it is named.
    named = {}
    for excess_db in (10.0, None):
        mon = ReflectorMonitor(world, CFG.model_copy(update={"mask_excess_db": excess_db}), 20.0)
        xy = _visible_xy(world, mon, np.random.default_rng(3), min_gap_m=0.55)
        d = world.layout.distances_m(world.radar_position(xy))
        det = _detections([*d, d[2] + 0.2], [0.0] * len(d) + [30.0])
        for _ in range(60):
            mon.update(_estimate(xy), _gated(world, xy, drop=[2]), detections=det)
        named[excess_db] = mon.suspects
    assert named[10.0] == () and named[None] == (2,)


def test_a_moved_reflector_is_named_in_a_room_with_an_obstacle():
    """A room with a box needs the visibility model and its survey; naming a moved reflector
    there rebuilds the model without it, survey and all (it crashed on the survey's shape)."""
    box = {"min": [1.2, 1.2, 0.0], "max": [2.3, 2.8, 1.0]}  # inside the patrol loop
    over = {
        "room": {"obstacles": [box]},
        "perturbations": {"displaced_reflector": {"severity": 1.0}},
    }
    env, named = _patrol(over, seed=0)
    moved = set(env.perturbations["displaced_reflector"].moved.tolist())
    assert set(named) == moved
    model = env.localizer.model
    assert sum(model.counts) == len(env.world.layout) - 1
    assert model.link.delivery is not None and len(model.link.delivery) == sum(model.counts)
