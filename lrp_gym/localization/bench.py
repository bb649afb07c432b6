"""Speed of one AMCL update (motion + likelihood + estimate + resample) on one core."""

from __future__ import annotations

import time

import numpy as np

from lrp_gym.config import ScenarioConfig
from lrp_gym.localization.amcl import Amcl
from lrp_gym.tracking.fingerprint import Fingerprint
from lrp_gym.world.robot import odometry_delta
from lrp_gym.world.world import World


def _time_updates(amcl: Amcl, steps, seconds: float, rng, fixed_n: int | None) -> float:
    """Mean milliseconds per update; the particle set is restored to ``fixed_n`` before each."""
    state = (amcl.particles.copy(), amcl.weights.copy())
    times: list[float] = []
    deadline = time.perf_counter() + seconds
    i = 0
    while time.perf_counter() < deadline or len(times) < 5:
        od, fp = steps[i % len(steps)]
        i += 1
        if fixed_n is not None:
            amcl.particles, amcl.weights = state[0].copy(), state[1].copy()
        t0 = time.perf_counter()
        amcl.update(od, fp, rng)
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def bench_amcl(cfg: ScenarioConfig, seconds: float) -> dict:
    """Time AMCL updates on true fingerprints around a loop: 12 poses on a 0.8 m circle about
    the room centre, heading along the circle (0.41 m and 30 degrees between poses).

    Returns
    -------
    dict
        ``amcl_update_ms_10000``: median time of one full update with 10000 particles (global
        localisation phase, resampling forced every update); ``amcl_update_ms_converged``:
        median update time once the KLD count has settled; ``amcl_converged_particles``:
        that count.
    """
    world = World.from_config(cfg)
    loc = cfg.localization.model_copy(update={"resample_ess_ratio": 1.0})
    rng = np.random.default_rng(0)
    # A short loop of true poses around the room centre.
    c = world.room.size_m[:2] / 2.0
    ang = np.linspace(0.0, 2.0 * np.pi, 13)[:-1]
    poses = np.column_stack([c[0] + 0.8 * np.cos(ang), c[1] + 0.8 * np.sin(ang), ang + np.pi / 2])
    steps = []
    for k in range(len(poses)):
        od = odometry_delta(poses[k - 1], poses[k])
        fp = Fingerprint.from_true(world.layout, world.radar_position(poses[k, :2]))
        steps.append((od, fp))
    fixed = {"initial_particles": 10000, "min_particles": 10000, "max_particles": 10000}
    amcl = Amcl(world, loc.model_copy(update=fixed))
    amcl.reset(rng)
    ms_full = _time_updates(amcl, steps, seconds / 2.0, rng, fixed_n=10000)
    amcl = Amcl(world, loc)
    amcl.reset(rng)
    for k in range(30):  # settle the KLD count
        amcl.update(*steps[k % len(steps)], rng)
    n_conv = len(amcl.particles)
    ms_conv = _time_updates(
        amcl, steps[30 % len(steps) :] + steps, seconds / 2.0, rng, fixed_n=None
    )
    return {
        "amcl_update_ms_10000": ms_full,
        "amcl_update_ms_converged": ms_conv,
        "amcl_converged_particles": int(np.median([n_conv, len(amcl.particles)])),
    }
