"""The tracker's stacked Kalman equations agree with filterpy's KalmanFilter on the same inputs."""

import numpy as np
import pytest
from filterpy.common import Q_discrete_white_noise
from filterpy.kalman import KalmanFilter

from lrp_gym.tracking.kalman import kalman_predict, kalman_update


def _random_states(rng, n):
    x = np.column_stack([rng.uniform(0.5, 8.0, n), rng.uniform(-2.0, 2.0, n)])
    A = rng.normal(size=(n, 2, 2)) * 0.2
    P = A @ A.transpose(0, 2, 1) + 1e-3 * np.eye(2)  # symmetric positive definite
    return x, P


def _filterpy(x, P, R):
    kf = KalmanFilter(dim_x=2, dim_z=2)
    kf.x, kf.P, kf.H, kf.R = x.reshape(2, 1).copy(), P.copy(), np.eye(2), R
    return kf


@pytest.mark.parametrize("dt_s", [0.05, 0.5])
def test_predict_then_update_match_filterpy(dt_s):
    rng = np.random.default_rng(3)
    n = 7
    x, P = _random_states(rng, n)
    R = np.diag([0.05**2, 0.1**2])
    F = np.array([[1.0, dt_s], [0.0, 1.0]])
    Q = Q_discrete_white_noise(2, dt=dt_s, var=0.8**2)
    z = x + rng.normal(scale=[0.3, 0.5], size=(n, 2))

    xp, Pp = kalman_predict(x, P, F, Q)
    xu, Pu = kalman_update(xp, Pp, z, R)
    for i in range(n):
        kf = _filterpy(x[i], P[i], R)
        kf.predict(F=F, Q=Q)
        np.testing.assert_allclose(xp[i], kf.x[:, 0], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(Pp[i], kf.P, rtol=1e-12, atol=1e-14)
        kf.update(z[i].reshape(2, 1))
        np.testing.assert_allclose(xu[i], kf.x[:, 0], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(Pu[i], kf.P, rtol=1e-12, atol=1e-14)


def test_update_shrinks_uncertainty_toward_measurement():
    # With equal prior and measurement variance the posterior is the midpoint at half variance.
    x = np.array([[2.0, 0.0]])
    P = np.eye(2)[None] * 0.04
    R = np.eye(2) * 0.04
    xu, Pu = kalman_update(x, P, np.array([[2.2, 0.4]]), R)
    np.testing.assert_allclose(xu, [[2.1, 0.2]])
    np.testing.assert_allclose(Pu[0], np.eye(2) * 0.02)
