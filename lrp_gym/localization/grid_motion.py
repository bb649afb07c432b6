"""AMCL's odometry motion model on a histogram over (heading, x, y).

A particle moves by the noisy odometry ``(rot1 + e1, trans + e2, rot2 + e3)`` with
``e ~ N(0, diag(OdometryNoise.std(odometry)^2))`` (:func:`~lrp_gym.localization.particle_motion.sample_motion`).
On a grid the same model is two convolutions:

1. *translation*, per heading slice ``th_k``: the displacement
   ``(trans + e2) (cos(th_k + rot1 + e1), sin(th_k + rot1 + e1))`` does not depend on the
   position, so each slice is convolved with its own kernel. The kernel is the exact nonlinear
   displacement evaluated on a lattice of ``(e1, e2)`` nodes (Gaussian weights, spacing at most
   half a cell at the far end of the move) and splatted bilinearly into the cells. The
   bilinear splat is the transition between cells when the mass is uniform within its source
   cell, so a noise-free move by a fraction of a cell spreads a delta to the neighbouring cells
   in proportion, instead of leaving it stuck. The heading's own spread within its cell
   (uniform over ``dth``) adds ``dth^2 / 12`` to the variance of ``e1`` here;
2. *rotation*: a circular convolution of the heading axis with the distribution of
   ``rot1 + rot2 + e1 + e3`` (same node-and-splat construction, in one dimension).

Approximation: the two steps draw ``e1`` independently, so the correlation between the
lateral displacement and the new heading that one ``e1`` gives a particle is lost (the
marginals in position and in heading are right). Mass moved out of the grid is dropped; the
caller zeroes the cells outside the free space, as AMCL zeroes particles that leave it.
Convolutions run by FFT (``scipy.signal.fftconvolve``); their round-off, about 1e-16 of each
slice's largest value, is clipped at zero.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import fftconvolve

#: Gaussian nodes reach this many standard deviations.
_N_SIGMA = 4.0
#: Upper bound on the nodes per noise axis (a very long move with a wide turn noise).
_MAX_NODES = 401


def gaussian_nodes(std: float, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Offsets and weights (summing to 1) of a zero-mean Gaussian on a lattice.

    The lattice spans ``+-4 std`` with at most ``spacing`` between nodes; a single node at 0
    when that span is below ``spacing`` (the noise does not move mass between cells).
    """
    if not (std > 0.0 and _N_SIGMA * std > 0.5 * spacing):
        return np.zeros(1), np.ones(1)
    half = min(int(np.ceil(_N_SIGMA * std / spacing)), _MAX_NODES // 2)
    z = np.linspace(-_N_SIGMA * std, _N_SIGMA * std, 2 * half + 1)
    w = np.exp(-0.5 * (z / std) ** 2)
    return z, w / w.sum()


def _splat_1d(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lower cell index and the upper cell's share for positions ``u`` in cell units."""
    i0 = np.floor(u)
    return i0.astype(np.int64), u - i0


def translation_kernels(
    headings_rad: np.ndarray, odometry: np.ndarray, std: np.ndarray, cell_m: float, cell_rad: float
) -> tuple[np.ndarray, int]:
    """Per heading slice, the distribution of the xy displacement in cells.

    Parameters
    ----------
    headings_rad : ndarray (H,)
        Heading of each slice (cell centre).
    odometry : ndarray (3,)
        (rot1_rad, trans_m, rot2_rad).
    std : ndarray (3,)
        Standard deviations of (rot1, trans, rot2) (:meth:`OdometryNoise.std`).
    cell_m, cell_rad : float
        Cell size in x and y (m) and in heading (rad).

    Returns
    -------
    kernels : ndarray (H, 2R+1, 2R+1)
        ``kernels[k, R + di, R + dj]`` = probability that mass of slice ``k`` moves by
        ``(di, dj)`` cells; each kernel sums to 1.
    radius : int
        ``R`` in cells.
    """
    rot1, trans = float(odometry[0]), float(odometry[1])
    e2, w2 = gaussian_nodes(float(std[1]), 0.5 * cell_m)
    reach = abs(trans) + float(np.max(np.abs(e2)))
    s1 = float(np.hypot(std[0], cell_rad / np.sqrt(12.0)))
    # Node spacing in e1 so that the far end of the move steps at most half a cell.
    e1, w1 = gaussian_nodes(s1, 0.5 * cell_m / max(reach, 1e-12))
    radius = int(np.ceil(reach / cell_m)) + 1
    size = 2 * radius + 1
    phi = headings_rad[:, None, None] + rot1 + e1[None, :, None]  # (H, n1, 1)
    r = (trans + e2)[None, None, :]  # (1, 1, n2)
    ix, fx = _splat_1d(r * np.cos(phi) / cell_m + radius)
    iy, fy = _splat_1d(r * np.sin(phi) / cell_m + radius)
    w = np.broadcast_to((w1[:, None] * w2[None, :])[None], ix.shape)
    base = np.arange(len(headings_rad))[:, None, None] * size * size
    flat = np.zeros(len(headings_rad) * size * size)
    for di, wx in ((0, 1.0 - fx), (1, fx)):
        for dj, wy in ((0, 1.0 - fy), (1, fy)):
            idx = base + (ix + di) * size + (iy + dj)
            flat += np.bincount(idx.ravel(), (w * wx * wy).ravel(), minlength=flat.size)
    return flat.reshape(len(headings_rad), size, size), radius


def heading_kernel(n_headings: int, odometry: np.ndarray, std: np.ndarray) -> np.ndarray:
    """Circular kernel (H,): probability that the heading moves by ``k`` cells (mod H)."""
    cell_rad = 2.0 * np.pi / n_headings
    s = float(np.hypot(std[0], std[2]))
    e, w = gaussian_nodes(s, 0.5 * cell_rad)
    i0, f = _splat_1d((float(odometry[0]) + float(odometry[2]) + e) / cell_rad)
    out = np.bincount(i0 % n_headings, w * (1.0 - f), minlength=n_headings)
    out += np.bincount((i0 + 1) % n_headings, w * f, minlength=n_headings)
    return out


def convolve_xy(density: np.ndarray, kernels: np.ndarray, radius: int) -> np.ndarray:
    """Move each heading slice of ``density`` (H, nx, ny) by its kernel; mass leaving the grid
    is dropped. Returns a new array (or ``density`` itself when every kernel is the identity)."""
    if np.all(kernels[:, radius, radius] == 1.0):
        return density
    nx, ny = density.shape[1:]
    out = fftconvolve(density, kernels, mode="full", axes=(1, 2))
    out = out[:, radius : radius + nx, radius : radius + ny]
    return np.maximum(out, 0.0, out=out)


def convolve_heading(density: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """Circular convolution of the heading axis (axis 0) of ``density`` with ``kernel`` (H,)."""
    if kernel[0] == 1.0:
        return density
    n = density.shape[0]
    spec = np.fft.rfft(density, axis=0) * np.fft.rfft(kernel)[:, None, None]
    out = np.fft.irfft(spec, n=n, axis=0)
    return np.maximum(out, 0.0, out=out)
