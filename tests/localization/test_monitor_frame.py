"""How the monitor associates a frame's returns with the mapped reflectors."""

from __future__ import annotations

import numpy as np

from lrp_gym.localization.monitor_frame import doppler_residuals, nearest_residuals


def test_the_nearest_return_gives_the_residual_and_none_gives_inf():
    predicted = np.array([2.0, 4.0])
    assert np.allclose(nearest_residuals(predicted, np.array([2.05, 3.7, 4.2])), [0.05, 0.2])
    assert np.isinf(nearest_residuals(predicted, np.zeros(0))).all()


def test_the_parity_residual_skips_a_nearer_return_at_another_radial_velocity():
    # Reflector 0 (expected at -0.5 m/s): a structure return 2 cm away moves at +0.4 m/s, its
    # own return 12 cm away at -0.48: the own one is taken. Reflector 1: nothing fits its
    # velocity, so the nearest return stands.
    predicted = np.array([3.0, 5.0])
    z = np.array([3.02, 3.12, 4.9, 5.3])
    v = np.array([0.4, -0.48, 0.9, 1.0])
    r = doppler_residuals(predicted, z, v, np.array([-0.5, -1.0]), tolerance_mps=0.45)
    assert np.allclose(r, [0.12, -0.1])
