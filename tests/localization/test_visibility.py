"""The likelihood knows which reflectors a position can see (obstacles, pattern, range)."""

from __future__ import annotations

import numpy as np
import pytest

from lrp_gym.config import load_scenario
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.likelihood import FingerprintModel
from lrp_gym.localization.visibility import RadarLink, ReflectorVisibility
from lrp_gym.radar.paths import Paths
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world import Box, Room, World
from lrp_gym.world.reflectors import ReflectorLayout, ReflectorType

TRIHEDRAL = ReflectorType("A", "trihedral", 1.0, half_angle_deg=20.0, cutoff_deg=60.0)
DOWN = [0.0, 0.0, -1.0]


def _layout(positions, axes=None) -> ReflectorLayout:
    positions = np.asarray(positions, float)
    axes = np.tile(DOWN, (len(positions), 1)) if axes is None else axes
    return ReflectorLayout(positions, np.zeros(len(positions), int), axes, (TRIHEDRAL,))


def test_a_box_on_the_line_of_sight_hides_a_reflector_and_one_below_it_does_not():
    layout = _layout([[1.0, 2.0, 3.0]])
    # From (3, 2) at 0.3 m the line to (1, 2, 3) is at 0.3 + 2.7 * 0.5 / 2 = 0.975 m above
    # x = 2.5: a box from x = 2.4 to 2.6 that is 1.2 m tall crosses it, one 0.8 m tall does not.
    for height, seen in ((1.2, False), (0.8, True)):
        room = Room(np.array([5.0, 5.0, 4.0]), (Box([2.4, 1.5, 0.0], [2.6, 2.5, height]),))
        vis = ReflectorVisibility(room, layout, 0.3, 10.0)
        assert vis.visible(np.array([[3.0, 2.0]])).tolist() == [[seen]]
        # On the near side of the box nothing is between.
        assert vis.visible(np.array([[1.5, 2.0]])).tolist() == [[True]]


def test_pattern_cutoff_and_range_hide_a_reflector():
    room = Room(np.array([8.0, 8.0, 4.0]))
    layout = _layout([[1.0, 1.0, 3.0]])
    vis = ReflectorVisibility(room, layout, 0.3, 6.0)
    # Straight below: incidence 0; 2.7 m below and 2.7 * tan(60 deg) = 4.68 m away: the cutoff.
    got = vis.visible(np.array([[1.0, 1.0], [1.0 + 4.6, 1.0], [1.0 + 4.8, 1.0]]))
    assert got.tolist() == [[True, True, False]]
    # Range: the radar sees 6 m; 4.6 m across and 2.7 m up is 5.33 m, in range.
    short = ReflectorVisibility(room, layout, 0.3, 5.0)
    assert short.visible(np.array([[1.0 + 4.6, 1.0]])).tolist() == [[False]]


def test_the_paper_room_needs_no_visibility_model():
    world = World.from_config(load_scenario("ipin2023"))
    assert ReflectorVisibility.for_world(world) is None
    obstructed = load_scenario("ipin2023").with_overrides(
        {"room": {"obstacles": [{"min": [0.8, 1.4, 0.0], "max": [2.2, 2.6, 1.0]}]}}
    )
    assert ReflectorVisibility.for_world(World.from_config(obstructed)) is not None


@pytest.mark.parametrize("doppler", [False, True])
@pytest.mark.parametrize("extra_m", [None, 2.2])
def test_a_hidden_reflector_counts_as_absent(doppler, extra_m):
    """Where a box hides reflector 0, the model with visibility equals, at that position, the
    plain model of the layout without reflector 0 in which clutter keeps its expected number
    of returns: the sorted assignment of the seen ones, their mixture, no cost for the hidden
    one's silence, and a clutter share of c / (1 - (1 - c) / 4) (one of four reflectors' share
    of the returns gone)."""
    positions = [[1.0, 2.0, 3.0], [4.2, 0.8, 3.0], [4.0, 4.3, 3.0], [2.0, 4.5, 3.0]]
    layout = _layout(positions, axes=np.tile(DOWN, (4, 1)))
    room = Room(np.array([5.0, 5.0, 4.0]), (Box([2.4, 1.5, 0.0], [2.6, 2.5, 1.2]),))
    xy = np.array([[3.0, 2.0], [3.05, 1.95]])
    vis = ReflectorVisibility(room, layout, 0.3, 10.0)
    assert vis.visible(xy)[:, 0].tolist() == [False, True, True, True]

    def model(lay, visibility, clutter=0.05):
        return FingerprintModel(
            lay, 0.3, 0.05, clutter, 10.0, doppler_std_mps=0.15 if doppler else 0.0,
            detection_probability=0.8, visibility=visibility,
        )  # fmt: skip

    seen = _layout(positions[1:], axes=np.tile(DOWN, (3, 1)))
    radar = np.array([3.0, 2.0, 0.3])
    d = np.sort(np.linalg.norm(np.asarray(positions[1:]) - radar, axis=1)) + 0.01
    if extra_m is not None:
        d = np.sort(np.r_[d, extra_m])
    v = np.full(len(d), 1e-4)
    vel = np.linspace(-0.3, 0.3, len(d)) if doppler else None
    fp = Fingerprint(("A",), (d,), (v,), (np.ones(len(d), bool),), None if vel is None else (vel,))
    velocity_xy = np.array([[0.3, 0.1]] * 2) if doppler else None
    got = model(layout, vis).log_likelihood(xy[:1], fp, velocity_xy=_first(velocity_xy))
    clutter = 0.05 / (1.0 - 0.95 / 4)
    want = model(seen, None, clutter).log_likelihood(xy[:1], fp, velocity_xy=_first(velocity_xy))
    np.testing.assert_allclose(got, want, rtol=1e-5)
    # Without the visibility, the silent reflector costs log(1 - P_D) there and the frame's
    # three distances cannot take the sorted assignment of four.
    plain = model(layout, None).log_likelihood(xy[:1], fp, velocity_xy=_first(velocity_xy))
    assert plain[0] < got[0] - 1.0


def _first(a):
    return None if a is None else a[:1]


def _single_path(range_m: float, power_w: float) -> Paths:
    one = np.ones(1)
    return Paths(range_m * one, 0.3 * one, power_w * one, 0.0 * one, -2 * one.astype(int),
                 0 * one.astype(int), 4 * one.astype(int))  # fmt: skip


@pytest.mark.parametrize("fidelity", ["detections", "signal"])
def test_the_links_detection_probability_is_the_radars_for_a_lone_return(fidelity):
    """One return in noise: the share of frames the radar detects it (within one range cell)
    is the probability the link predicts from its SNR, from near 0 to near 1."""
    cfg = load_scenario("ipin2023")
    world = World.from_config(cfg)
    sensor = RadarSensor(world, cfg.radar.model_copy(update={"fidelity": fidelity}))
    link = RadarLink.from_sensor(sensor)
    rng = np.random.default_rng(3)
    frames = 400 if fidelity == "detections" else 60
    res = sensor.fmcw.range_resolution_m
    predicted = []
    for snr_db in (10.0, 12.5, 15.0, 20.0):
        power_w = 10.0 ** (snr_db / 10.0) / link.snr_per_w
        hits = 0
        for _ in range(frames):
            range_m = 3.0 + rng.uniform(0.0, res)  # a random sub-bin offset
            paths = _single_path(range_m, power_w)
            det = sensor.detect(paths, rng)
            hits += bool(np.any(np.abs(det.range_m - range_m) < res))
        # The power at which the radar equation gives this SNR, as a point target would.
        rcs = power_w * (4 * np.pi) ** 3 * 3.0**4 / link.link_w_m2
        p = float(link.detection_probability(np.array(rcs), np.array(3.0), np.array(1.0)))
        predicted.append(p)
        tol = 3.0 * np.sqrt(max(p * (1 - p), 0.02) / frames) + 0.03
        assert abs(hits / frames - p) < tol, (fidelity, snr_db, hits / frames, p)
    assert predicted[0] < 0.3 and predicted[-1] > 0.99


class _Fixed:
    """A visibility that gives fixed detection probabilities (M,) at every position."""

    def __init__(self, p):
        self.p = np.asarray(p, float)

    def detection_probability(self, xy):
        return np.repeat(self.p[:, None], len(xy), axis=1)


def test_a_reflectors_silence_costs_what_its_detection_probability_says(loc_world):
    """Certain detection everywhere: the plain model. Reflector 0 silent with detection
    probability q: its cost is log(1 - P_D q) instead of log(1 - P_D)."""
    lay = loc_world.layout
    xy = np.array([[2.0, 3.0], [2.5, 1.5]])
    radar = loc_world.radar_position(xy[0])
    d = np.sort(lay.distances_m(radar)[1:])  # reflector 0 missed
    fp = Fingerprint(("A",), (d,), (np.full(3, 1e-4),), (np.ones(3, bool),))

    def model(vis):
        return FingerprintModel(lay, loc_world.mount_height_m, 0.05, 0.05, 10.0,
                                detection_probability=0.8, visibility=vis)  # fmt: skip

    plain = model(None).log_likelihood(xy, fp)
    np.testing.assert_allclose(model(_Fixed([1, 1, 1, 1])).log_likelihood(xy, fp), plain, rtol=1e-5)
    q = 0.3
    got = model(_Fixed([q, 1, 1, 1])).log_likelihood(xy[:1], fp)
    # (reflector 0 is 0.22 m from the nearest distance: its kernel is about 1e-4, not 0)
    np.testing.assert_allclose(got - plain[:1], np.log1p(-0.8 * q) - np.log1p(-0.8), atol=2e-3)


def test_amcl_localises_where_the_box_hides_three_reflectors():
    """The failure the model fixes: standing where a box hides 3 of the 4 reflectors, with an
    ideal radar's fingerprint (the one reflector in view), AMCL from an unknown start ends near
    the truth; the model that expects every reflector everywhere puts it metres away."""
    box = {"min": [0.8, 1.4, 0.0], "max": [2.2, 2.6, 1.0]}
    cfg = load_scenario("ipin2023").with_overrides(
        {"room": {"obstacles": [box]}, "localization": {"initial_particles": 2000}}
    )
    world = World.from_config(cfg)
    vis = ReflectorVisibility.of(world)
    spots = np.array([[1.0, 1.0], [1.2, 0.9], [1.4, 1.1]])
    assert ((~vis.visible(spots)).sum(axis=0) == 3).all()
    near = {}
    for on in (True, False):
        loc = cfg.localization.model_copy(update={"reflector_visibility": on})
        hits = 0
        for k, xy in enumerate(spots):
            rng = np.random.default_rng(k)
            amcl = Amcl(world, loc)
            amcl.reset(rng)
            seen = vis.visible(xy[None])[:, 0]
            fp = Fingerprint.from_true(world.layout, world.radar_position(xy), 0.02, seen)
            for _ in range(6):
                est = amcl.update(np.zeros(3), fp, rng)
            hits += np.hypot(*(est.pose[:2] - xy)) < 0.3
        near[on] = hits
    assert near == {True: len(spots), False: 0}, near


def test_the_map_interpolates_the_exact_probabilities():
    """The tabulated probabilities equal the exact ones on the table's nodes and stay close
    between them (they differ only within a cell of a shadow's edge)."""
    cfg = load_scenario("ipin2023").with_overrides(
        {"room": {"obstacles": [{"min": [0.8, 1.4, 0.0], "max": [2.2, 2.6, 1.0]}]}}
    )
    world = World.from_config(cfg)
    link = RadarLink.from_sensor(RadarSensor(world, cfg.radar))
    vmap = ReflectorVisibility.for_world(world, link)
    xy = np.random.default_rng(0).uniform(0.2, 4.8, (4000, 2))
    xy = xy[world.room.free(xy)]
    exact, tabled = vmap.exact.detection_probability(xy), vmap.detection_probability(xy)
    assert np.abs(tabled - exact).mean() < 0.005
    assert np.mean(np.abs(tabled - exact) > 0.5) < 0.005
    nodes = np.array([[1.0, 1.0], [3.0, 4.0]])  # multiples of the 2.5 cm cell
    np.testing.assert_allclose(
        vmap.detection_probability(nodes), vmap.exact.detection_probability(nodes), atol=1e-6
    )


def test_a_survey_scales_each_reflector_down_to_its_delivered_rate_in_view():
    """``detection_survey_poses``: the likelihood's detection probability of each reflector,
    ``P_D p_j``, averages to the rate at which the radar delivered it in view where that is
    below ``P_D``, at least 0.05; a reflector never in view or delivered more often keeps
    ``P_D``."""
    from lrp_gym.localization.factory import radar_link
    from lrp_gym.radar.delivery_rate import lrp_detection_rate

    link = RadarLink(1.0, None, False, 1.0, 0.0, np.ones(3))
    scaled = link.surveyed(np.array([0.4, 0.99, np.nan, 0.0]), 0.8)
    np.testing.assert_allclose(scaled.delivery * 0.8, [0.4, 0.8, 0.8, 0.05])
    box = {"min": [0.8, 1.4, 0.0], "max": [2.2, 2.6, 1.0]}
    cfg = load_scenario("ipin2023").with_overrides(
        {
            "room": {"obstacles": [box]},
            "radar": {"fidelity": "detections"},
            "localization": {"detection_survey_poses": 60},
        }
    )
    link = radar_link(cfg, RadarSensor(World.from_config(cfg), cfg.radar))
    rates = np.array(lrp_detection_rate(cfg, 60, seed=0).per_lrp_in_view_rate)
    np.testing.assert_allclose(link.delivery * 0.8, np.clip(rates, 0.05, 0.8))
    off = cfg.with_overrides({"localization": {"detection_survey_poses": 0}})
    assert radar_link(off, RadarSensor(World.from_config(off), off.radar)).delivery is None
    # The default surveys, but not a room whose reflectors are detected everywhere.
    paper = load_scenario("ipin2023")
    assert paper.localization.detection_survey_poses > 0
    assert radar_link(paper, RadarSensor(World.from_config(paper), paper.radar)).delivery is None


def test_a_model_without_a_suspect_keeps_the_others_survey():
    """The reflector monitor's model without reflector 1, in a surveyed room: the kept
    reflectors keep their survey's scaling, reflector 1's is dropped with it (it crashed on
    the mismatched shapes when a suspect was named in a surveyed room)."""
    from lrp_gym.localization.reflector_monitor import model_without

    box = {"min": [0.8, 1.4, 0.0], "max": [2.2, 2.6, 1.0]}
    cfg = load_scenario("ipin2023").with_overrides({"room": {"obstacles": [box]}})
    world = World.from_config(cfg)
    link = RadarLink.from_sensor(RadarSensor(world, cfg.radar))
    surveyed = link.surveyed(np.array([0.2, 0.4, 0.6, 0.8]), 0.8)
    reduced = model_without(world, cfg.localization, (1,), surveyed)
    np.testing.assert_allclose(reduced.link.delivery, [0.25, 0.75, 1.0])
    xy = np.array([[0.5, 0.5], [3.5, 3.5], [2.5, 1.0]])
    full = FingerprintModel.for_world(world, cfg.localization, surveyed).visibility.exact
    np.testing.assert_allclose(
        reduced.visibility.exact.detection_probability(xy),
        full.detection_probability(xy)[[0, 2, 3]],
        rtol=1e-12,
    )
