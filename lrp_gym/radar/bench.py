"""Speed of the radar chain on one core: signal-level and detections-level frames per second."""

from __future__ import annotations

import time

import numpy as np

from lrp_gym.config import ScenarioConfig
from lrp_gym.radar.sensor import RadarSensor
from lrp_gym.world.world import World


def limit_blas_threads(n: int = 1) -> bool:
    """Limit numpy's bundled OpenBLAS to ``n`` threads (ctypes); False if it cannot.

    The cube's (samples x paths) @ (paths x chirps) product is small; OpenBLAS' threads make
    it 20-80x slower when the other core is busy, so one-core figures need this.
    """
    import ctypes
    import glob
    import os

    libdir = os.path.join(os.path.dirname(np.__file__), os.pardir, "numpy.libs")
    for path in glob.glob(os.path.join(libdir, "libscipy_openblas*.so")):
        lib = ctypes.CDLL(path)
        for name in ("scipy_openblas_set_num_threads64_", "openblas_set_num_threads"):
            fn = getattr(lib, name, None)
            if fn is not None:
                fn(ctypes.c_int(n))
                return True
    return False


def _rate(sensor, poses: np.ndarray, vels: np.ndarray, seconds: float) -> float:
    rng = np.random.default_rng(0)
    for p, v in zip(poses[:5], vels[:5], strict=True):  # warm-up (caches, FFT plans)
        sensor.measure(p, v, rng)
    n, start = 0, time.perf_counter()
    while True:
        i = n % len(poses)
        sensor.measure(poses[i], vels[i], rng)
        n += 1
        elapsed = time.perf_counter() - start
        if elapsed >= seconds:
            return n / elapsed


def bench_radar(cfg: ScenarioConfig, seconds: float) -> dict:
    """Frames per second of channel + signal + processing, and of the detections fidelity.

    Uses the scenario with noise on and its configured reflection order, on random free poses
    moving at up to the robot's top speed.
    """
    blas_limited = limit_blas_threads(1)
    world = World.from_config(cfg)
    rng = np.random.default_rng(1)
    xy = rng.uniform(0.0, 1.0, (400, 2)) * world.room.size_m[:2]
    xy = xy[world.room.free(xy, 0.05)][:64]
    th = rng.uniform(-np.pi, np.pi, len(xy))
    speed = rng.uniform(0.0, cfg.robot.max_speed_mps, len(xy))
    poses = np.column_stack([xy, th])
    vels = speed[:, None] * np.column_stack([np.cos(th), np.sin(th)])
    out: dict = {"radar_blas_single_thread": blas_limited}
    for key, fidelity in (
        ("radar_frames_per_s", "signal"),
        ("radar_fast_frames_per_s", "detections"),
    ):
        radar = cfg.radar.model_copy(update={"fidelity": fidelity, "noise": True})
        out[key] = _rate(RadarSensor(world, radar), poses, vels, seconds / 2.0)
    sensor = RadarSensor(world, cfg.radar.model_copy(update={"fidelity": "signal"}))
    out["radar_paths_per_frame"] = float(
        np.mean([len(sensor.paths(p, v)) for p, v in zip(poses, vels, strict=True)])
    )
    return out
