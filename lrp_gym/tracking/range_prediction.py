"""How the distance to a static reflector changes while the robot moves: the tracker's prediction.

A reflector is a fixed point; the radar measures its distance ``r`` and the rate ``r_dot`` (the
radial velocity). In the robot frame at the previous radar frame, with the robot's velocity
``(u, 0)`` along its heading, the Doppler pins down the along-track coordinate of the reflector,
``p_x = -r * r_dot / u``, and its known height pins down the horizontal distance
``rho = sqrt(r**2 - dz**2)``; only the side, ``p_y = +-sqrt(rho**2 - p_x**2)``, is unknown. The
odometry since that frame, ``(rot1, trans, rot2)``, moves the robot by
``trans * (cos rot1, sin rot1)`` and turns it by ``rot1 + rot2``, so::

    r'**2 = r**2 - 2 * trans * (p_x * cos(rot1) + p_y * sin(rot1)) + trans**2

exactly, for both sides; the new rate follows from the new heading and speed. While the robot
drives straight (``rot1 = 0``) the side does not matter, and this is the paper's linear motion
model made exact: the plain constant-velocity prediction ``r + r_dot * dt`` ignores the
``trans**2 * sin**2 / 2r`` term (3-4 cm per 0.5 m step for a reflector abeam). When the robot
turns, the two sides give two predictions; their mean is the prediction and half their
difference adds to its uncertainty.

What does not behave like a fixed point - the ceiling and a wall's specular point, which move
with the robot - is predicted wrongly by this model, and that is what lets the tracker tell
the reflectors from room returns of the same RCS.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_MIN_SPEED_MPS = 0.05  # below this the Doppler says nothing about the bearing


@dataclass(frozen=True)
class EgoMotion:
    """The robot's own motion, from its odometry: all the tracker needs to predict distances.

    Attributes
    ----------
    speed_mps : float
        Signed forward speed of the robot at this radar frame (what the Doppler of a static
        target is relative to; negative when reversing).
    odometry : ndarray, shape (3,)
        ``(rot1_rad, trans_m, rot2_rad)`` since the previous radar frame, as in
        :func:`lrp_gym.world.robot.odometry_delta`.
    """

    speed_mps: float
    odometry: np.ndarray

    def __post_init__(self) -> None:
        odo = np.asarray(self.odometry, dtype=float).reshape(-1)
        if odo.shape != (3,) or not np.all(np.isfinite(odo)):
            raise ValueError(f"odometry must be 3 finite numbers (rot1, trans, rot2), got {odo}")
        if not np.isfinite(self.speed_mps):
            raise ValueError(f"speed_mps must be finite, got {self.speed_mps}")
        object.__setattr__(self, "odometry", odo)
        object.__setattr__(self, "speed_mps", float(self.speed_mps))

    @classmethod
    def from_velocity(
        cls, velocity_xy_mps: np.ndarray, heading_rad: float, odometry: np.ndarray
    ) -> EgoMotion:
        """From the floor velocity and heading at the frame: the signed forward speed."""
        v = np.asarray(velocity_xy_mps, dtype=float)
        return cls(float(v[0] * np.cos(heading_rad) + v[1] * np.sin(heading_rad)), odometry)


def predict_static(
    range_m: np.ndarray,
    rate_mps: np.ndarray,
    height_m: np.ndarray,
    prev_speed_mps: float,
    ego: EgoMotion,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Predicted distance and rate of static points after the robot's motion ``ego``.

    Parameters
    ----------
    range_m, rate_mps : ndarray, shape (n,)
        Distance and radial velocity at the previous frame.
    height_m : ndarray, shape (n,)
        Height of each point above the radar (its reflector type's).
    prev_speed_mps : float
        Signed forward speed at the previous frame (the one ``rate_mps`` was measured at).
    ego : EgoMotion
        Motion since the previous frame and the speed at the new one.

    Returns
    -------
    range_m, rate_mps : ndarray, shape (n,)
        Predicted distance and rate (mean over the two sides).
    range_var_m2, rate_var : ndarray, shape (n,)
        Variance added by not knowing the side (zero while driving straight).
    """
    r = np.maximum(np.asarray(range_m, dtype=float), 1e-6)
    r_dot = np.asarray(rate_mps, dtype=float)
    rho2 = np.maximum(r * r - np.asarray(height_m, dtype=float) ** 2, 0.0)
    rot1, trans, rot2 = ego.odometry
    bearing_known = abs(prev_speed_mps) >= _MIN_SPEED_MPS
    if bearing_known:
        px = np.clip(-r * r_dot / prev_speed_mps, -np.sqrt(rho2), np.sqrt(rho2))
    else:
        px = np.zeros_like(r)  # no Doppler to go by: predict abeam, widen below
    py = np.sqrt(np.maximum(rho2 - px * px, 0.0))
    # The two candidate positions (p_x, +-p_y) relative to the robot after the move, in the
    # previous frame's axes; then the new heading and speed give the new radial velocity.
    qx = px - trans * np.cos(rot1)
    qy = np.stack([py, -py]) - trans * np.sin(rot1)
    dz2 = np.maximum(r * r - rho2, 0.0)
    r_new = np.sqrt(np.maximum(qx * qx + qy * qy + dz2, 1e-12))
    heading = rot1 + rot2
    rate_new = -ego.speed_mps * (qx * np.cos(heading) + qy * np.sin(heading)) / r_new
    range_var = (0.5 * (r_new[0] - r_new[1])) ** 2
    rate_var = (0.5 * (rate_new[0] - rate_new[1])) ** 2
    if not bearing_known:
        # A bearing uniform on the circle moves the distance by trans * cos(phi).
        range_var = range_var + 0.5 * trans**2
        rate_var = rate_var + 0.5 * ego.speed_mps**2
    return r_new.mean(axis=0), rate_new.mean(axis=0), range_var, rate_var


def ekf_predict_static(
    x: np.ndarray,
    P: np.ndarray,
    height_m: np.ndarray,
    prev_speed_mps: float,
    ego: EgoMotion,
    Q: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Extended-Kalman prediction of stacked tracks (n, 2), (n, 2, 2) as static points.

    The mean is :func:`predict_static`; its Jacobian comes from forward differences, and the
    spread of the two sides' predictions adds to the diagonal of ``J P J^T + Q``.
    """
    # One call on the state and its two forward-difference neighbours (for the Jacobian).
    n, eps = len(x), 1e-4
    xs = np.concatenate([x, x + [eps, 0.0], x + [0.0, eps]])
    r, v, var_r, var_v = predict_static(
        xs[:, 0], xs[:, 1], np.tile(height_m, 3), prev_speed_mps, ego
    )
    J = np.empty((n, 2, 2))
    J[:, 0, 0], J[:, 0, 1] = (r[n : 2 * n] - r[:n]) / eps, (r[2 * n :] - r[:n]) / eps
    J[:, 1, 0], J[:, 1, 1] = (v[n : 2 * n] - v[:n]) / eps, (v[2 * n :] - v[:n]) / eps
    P = J @ P @ J.transpose(0, 2, 1) + Q
    P[:, 0, 0] += var_r[:n]
    P[:, 1, 1] += var_v[:n]
    return np.column_stack([r[:n], v[:n]]), P


def static_doppler_ok(
    range_m: np.ndarray,
    velocity_mps: np.ndarray,
    min_height_m: np.ndarray,
    speed_mps: float,
    velocity_std_mps: float,
) -> np.ndarray:
    """Boolean (D, T): detection d's radial velocity is one a static reflector of type t can have.

    A point ``dz`` (``min_height_m[t]``) above the radar at range ``r`` closes at most at
    ``|u| * sqrt(1 - dz**2 / r**2)``; a wall approached head-on closes at the full speed. The
    bound is widened by three velocity standard deviations.
    """
    r = np.maximum(range_m[:, None], 1e-6)
    cos_elev = np.sqrt(np.maximum(1.0 - (min_height_m[None, :] / r) ** 2, 0.0))
    limit = abs(speed_mps) * cos_elev + 3.0 * velocity_std_mps
    return np.abs(velocity_mps[:, None]) <= limit
