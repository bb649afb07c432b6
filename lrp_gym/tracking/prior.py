"""Where the reflectors should appear, predicted from the positioning: map-aided identification.

The paper lets predictions identify the reflectors among the detections. The positioning
predicts every reflector's distance: a particle cloud as a mixture (one component per sampled
particle, so a cloud split between mirror-image poses predicts both), a pose with its
covariance as one Gaussian per reflector. A persistent return that sits at a predicted distance is far
more likely a reflector than one that does not (the ceiling, a wall-ceiling edge).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lrp_gym.world.reflectors import ReflectorLayout

#: Spread of a particle's predicted distance: the radar's range error plus the cloud's
#: granularity (a converged cloud is a few centimetres wide).
PARTICLE_KERNEL_STD_M = 0.05


@dataclass(frozen=True)
class DistancePrior:
    """Predicted distances of the reflectors as a mixture over pose hypotheses.

    Attributes
    ----------
    distance_m : ndarray, shape (S, M)
        Predicted distance of each reflector (layout order) under each of ``S`` hypotheses.
    std_m : ndarray, shape (S, M)
        Standard deviation of each prediction.
    weight : ndarray, shape (S,)
        Hypothesis weights (sum to 1).
    type_index : ndarray of int, shape (M,)
        Type of each reflector.
    confident : bool
        Whether the prediction may rank the tracks (a converged estimate). A prior that is
        not confident only vetoes tracks no hypothesis explains: right after a global start
        the heaviest mode of the cloud is often a mirror image of the true pose.
    """

    distance_m: np.ndarray
    std_m: np.ndarray
    weight: np.ndarray
    type_index: np.ndarray
    confident: bool = True

    @classmethod
    def from_pose(
        cls,
        layout: ReflectorLayout,
        mount_height_m: float,
        xy_m: np.ndarray,
        covariance_xy: np.ndarray,
    ) -> DistancePrior:
        """One hypothesis: a position ``xy_m`` (2,) with covariance ``covariance_xy`` (2, 2).

        The distance's gradient with respect to the position is the horizontal unit vector
        away from the reflector, scaled by ``rho / r``; first-order propagation gives the
        variance.
        """
        xy = np.asarray(xy_m, dtype=float).reshape(2)
        radar = np.array([xy[0], xy[1], mount_height_m])
        diff = radar - layout.positions_m  # (M, 3)
        dist = np.maximum(np.linalg.norm(diff, axis=1), 1e-6)
        grad = diff[:, :2] / dist[:, None]
        var = np.einsum("mi,ij,mj->m", grad, np.asarray(covariance_xy, dtype=float), grad)
        std = np.sqrt(np.maximum(var, 0.0))
        return cls(dist[None, :], std[None, :], np.ones(1), layout.type_index.copy())

    @classmethod
    def from_particles(
        cls,
        layout: ReflectorLayout,
        mount_height_m: float,
        xy_m: np.ndarray,
        weights: np.ndarray,
        max_hypotheses: int = 64,
        kernel_std_m: float = PARTICLE_KERNEL_STD_M,
        *,
        confident: bool = True,
    ) -> DistancePrior:
        """A particle cloud (N, 2) with weights (N,), thinned to ``max_hypotheses``.

        The thinning is systematic resampling with a fixed offset: deterministic, and it
        keeps every mode of the cloud in proportion to its weight.
        """
        xy = np.asarray(xy_m, dtype=float).reshape(-1, 2)
        w = np.asarray(weights, dtype=float).reshape(-1)
        if len(xy) == 0 or len(xy) != len(w) or not w.sum() > 0:
            raise ValueError("need as many positive-sum weights as particles (at least one)")
        if len(xy) > max_hypotheses:
            cdf = np.cumsum(w / w.sum())
            picks = (np.arange(max_hypotheses) + 0.5) / max_hypotheses
            xy = xy[np.minimum(np.searchsorted(cdf, picks), len(xy) - 1)]
            w = np.full(max_hypotheses, 1.0 / max_hypotheses)
        else:
            w = w / w.sum()
        radar = np.column_stack([xy, np.full(len(xy), mount_height_m)])
        dist = layout.distances_m(radar)
        return cls(dist, np.full(dist.shape, kernel_std_m), w, layout.type_index.copy(), confident)

    def log_density(self, type_index: int, distance_m: np.ndarray, variance_m2: np.ndarray):
        """Log density of tracked distances under each reflector's prediction, of a type.

        Parameters
        ----------
        type_index : int
        distance_m, variance_m2 : ndarray, shape (n,)
            Tracked distances and their variances (added to the prediction's).

        Returns
        -------
        ndarray, shape (n, M_t)
            ``log p(distance | reflector m)`` in 1/m, the mixture over the hypotheses.
        """
        refl = self.type_index == type_index
        mu = self.distance_m[:, refl]  # (S, Mt)
        var = np.asarray(variance_m2)[:, None, None] + self.std_m[None, :, refl] ** 2
        z2 = (np.asarray(distance_m)[:, None, None] - mu[None]) ** 2 / var
        with np.errstate(divide="ignore"):  # a hypothesis of weight 0 contributes exp(-inf)
            log_weight = np.log(self.weight)
        log_terms = -0.5 * (z2 + np.log(2.0 * np.pi * var)) + log_weight[None, :, None]
        peak = log_terms.max(axis=1)
        return peak + np.log(np.exp(log_terms - peak[:, None, :]).sum(axis=1))
