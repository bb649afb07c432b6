"""The lost test's second alternative: a heading-free filter over the grid's cells."""

import numpy as np
import pytest

from lrp_gym.localization.grid_alternative import UNIFORM_SHARE, GridAlternative
from lrp_gym.localization.proposal import LostTest, MeasurementGrid

CELL_M = 0.1


@pytest.fixture()
def grid():
    return MeasurementGrid(np.array([3.0, 2.0]), CELL_M, lambda xy: np.ones(len(xy), bool))


def _peak(grid, xy, height_nats=10.0, width_m=0.1):
    """A frame likelihood with one Gaussian peak at ``xy`` over a flat floor."""
    d2 = np.sum((grid.centres_m - np.asarray(xy)) ** 2, axis=1)
    return height_nats * np.exp(-d2 / (2 * width_m**2))


def test_cells_index_the_lattice(grid):
    assert len(grid) == 30 * 20
    back = (grid.cell_index + 0.5) * grid.cell_xy_m
    np.testing.assert_allclose(back, grid.centres_m)


def test_a_repeated_peak_is_found_and_then_predicted(grid):
    alt = GridAlternative(grid.cell_index, grid.cell_xy_m)
    ll = _peak(grid, (1.05, 0.95))
    first = alt.update(ll)
    # From the uniform prior the evidence is the mean likelihood: far below the peak.
    assert first == pytest.approx(np.log(np.mean(np.exp(ll))), abs=1e-6)
    for _ in range(5):
        last = alt.update(ll)
    # Concentrated on the peak, the filter predicts nearly the peak's own likelihood.
    assert last > ll.max() - 0.5
    assert grid.centres_m[np.argmax(alt.log_p)] == pytest.approx([1.05, 0.95])


def test_a_move_spreads_the_mass_as_a_ring_of_its_length_would(grid):
    alt = GridAlternative(grid.cell_index, grid.cell_xy_m)
    alt.log_p = np.where(np.all(np.isclose(grid.centres_m, [1.55, 0.95]), axis=1), 0.0, -np.inf)
    alt.move(0.3)
    alt.move(-0.3)  # the sign of the translation does not matter: 0.6 m in all
    alt.update(np.zeros(len(grid)))  # a flat frame: the posterior is the prediction
    p = np.exp(alt.log_p)
    var_x = np.sum(p * (grid.centres_m[:, 0] - 1.55) ** 2)
    # A ring of radius d has variance d^2 / 2 per axis (plus the cell's own 1/12).
    assert var_x == pytest.approx(0.6**2 / 2 + CELL_M**2 / 12, rel=0.1)
    assert alt.moved_m == 0.0


def test_after_a_kidnap_the_uniform_share_finds_the_robot_again(grid):
    alt = GridAlternative(grid.cell_index, grid.cell_xy_m)
    for _ in range(5):
        alt.update(_peak(grid, (0.55, 0.55)))
    far = _peak(grid, (2.45, 1.45))
    evidence = alt.update(far)
    # The jump costs at most log(cells / UNIFORM_SHARE) nats (13.3 here) once...
    assert evidence >= far.max() + np.log(UNIFORM_SHARE / len(grid)) - 1e-9
    # ...and a 10-nat peak takes the mass over in the next frame.
    alt.update(far)
    assert grid.centres_m[np.argmax(alt.log_p)] == pytest.approx([2.45, 1.45])


def test_elsewhere_is_beyond_the_radius_of_every_particle(grid):
    alt = GridAlternative(grid.cell_index, grid.cell_xy_m)
    cloud = np.array([[0.55, 0.55], [2.05, 1.05]])
    far = alt.far_from(cloud, np.array([0.5, 0.5]), 0.3)
    d = np.min(np.linalg.norm(grid.centres_m[:, None, :] - cloud[None], axis=2), axis=1)
    assert np.all(far[d > 0.45]) and not np.any(far[d < 0.3])
    assert np.sum(~far) == 2 * 7 * 7  # a 7 x 7 square of cells about each particle
    # A particle with under 1 % of the weight does not make its surroundings the cloud's.
    light = alt.far_from(cloud, np.array([0.995, 0.005]), 0.3)
    assert np.sum(~light) == 7 * 7
    assert light[np.argmin(np.linalg.norm(grid.centres_m - cloud[1], axis=1))]


def test_a_right_cloud_is_not_lost_however_sharp_the_likelihood(grid):
    """60 distances make each frame's likelihood so sharp that a cloud 3 cm off the best cell
    pays many nats against the filter's mass there. Weighed with all of its mass the filter
    would call the cloud lost; its mass near the cloud is not "elsewhere", so it does not."""
    ll = _peak(grid, (2.05, 1.05), height_nats=60.0, width_m=0.03)
    marginal = 60.0 * np.exp(-0.5)  # the peak's value 3 cm from its centre
    cloud = np.array([[2.08, 1.05]])

    def run(cloud_xy):
        test = LostTest(4.0, 8.0, alternative=GridAlternative(grid.cell_index, grid.cell_xy_m))
        for _ in range(20):
            test.move(0.03)
            w = None if cloud_xy is None else np.ones(len(cloud_xy))
            test.update_marginal(float(ll.max()), marginal, 60, ll, cloud_xy, w)
        return test.alternative_nats

    assert run(None) > 8.0
    assert run(cloud) == 0.0


def _cloud_at(grid, xy, ll):
    """The marginal of a tight cloud at ``xy``: the likelihood of its cell."""
    return float(ll[np.argmin(np.sum((grid.centres_m - np.asarray(xy)) ** 2, axis=1))])


def test_a_cloud_beaten_by_a_few_nats_every_frame_is_lost_for_the_second_statistic(grid):
    """Best cell 3 nats above the cloud in each frame: below the first statistic's drift of
    4, so it stays 0, while the alternative gains about 2 nats a frame and passes the
    threshold; a cloud on the peak never gains."""

    def run(cloud_xy):
        test = LostTest(4.0, 8.0, alternative=GridAlternative(grid.cell_index, grid.cell_xy_m))
        for _ in range(12):
            ll = _peak(grid, (2.05, 1.05), height_nats=3.0)
            test.move(0.03)
            marginal = _cloud_at(grid, cloud_xy, ll)
            test.update_marginal(float(ll.max()), marginal, 3, ll, np.array([cloud_xy]), [1.0])
        return test

    wrong, right = run((0.55, 0.55)), run((2.05, 1.05))
    assert wrong.statistic_nats == 0.0
    assert wrong.alternative_nats > 8.0 and wrong.p_lost > 0.5
    assert right.evidence_nats == 0.0 and right.p_lost < 0.01
    wrong.reset()
    assert wrong.evidence_nats == 0.0
    assert np.allclose(wrong.alternative.log_p, -np.log(len(grid)))


def test_the_lost_tests_std_adds_the_grids_quantisation():
    """A cell centre up to half a cell from the robot: the distance to a far reflector moves by
    the offset's projection, of variance (a^2 + b^2) / 24 over bearings (analytic); the lost
    test's model adds it to the weights' std, unless the config names a std of its own."""
    from lrp_gym.config import load_scenario
    from lrp_gym.localization.proposal import lost_test_std_m

    rng = np.random.default_rng(0)
    cell = np.array([0.1, 0.06])
    offset = (rng.random((200_000, 2)) - 0.5) * cell
    bearing = rng.uniform(-np.pi, np.pi, len(offset))
    shift = offset[:, 0] * np.cos(bearing) + offset[:, 1] * np.sin(bearing)
    loc = load_scenario("ipin2023").localization
    expected = np.sqrt(loc.measurement_std_m**2 + np.var(shift))
    assert lost_test_std_m(loc, cell) == pytest.approx(expected, rel=0.01)
    assert lost_test_std_m(loc) > loc.measurement_std_m  # the default 10 cm grid
    own = loc.model_copy(update={"lost_test_std_m": 0.05})
    assert lost_test_std_m(own, cell) == 0.05
