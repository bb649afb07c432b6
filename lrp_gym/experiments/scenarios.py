"""Random valid scenarios, seeded: rooms, obstacles, reflector catalogues, waveforms and paths.

:func:`random_scenario` draws what a new user might write: a 3-12 m room with 0-3 box
obstacles, 1-3 reflector kinds (sometimes one more type in the catalogue that no reflector
uses), 3-8 reflectors between 1.5 m and the ceiling, a waveform of 0.5-4 GHz bandwidth with
128-512 samples and 16-64 chirps whose range covers the room, and a 5-30 waypoint path whose
legs keep the robot clear of walls and obstacles. ``small=True`` keeps rooms, paths, the radar
frame and the particle count small enough for the test suite. :func:`random_perturbations`
adds a random set of robustness perturbations at random severities.

The result is built as a plain mapping and validated by :class:`~lrp_gym.config.ScenarioConfig`;
a draw that the validator rejects is a bug of the generator or of the validator, so it raises.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from lrp_gym.config import ScenarioConfig
from lrp_gym.config.perturbations import PerturbationsConfig
from lrp_gym.world.reflectors import REFLECTOR_KINDS
from lrp_gym.world.room import Box, Room

C_MPS = 299_792_458.0
#: Extra clearance of the generated path beyond the robot radius (pure pursuit cuts corners).
PATH_MARGIN_M = 0.1


def random_scenario(rng: np.random.Generator, *, small: bool = False) -> ScenarioConfig:
    """A random valid scenario.

    Parameters
    ----------
    rng : numpy.random.Generator
        The only source of randomness: the same generator state gives the same scenario.
    small : bool
        Rooms of 3-5 m, 3-5 waypoints 0.3-0.6 m apart, at most 256 samples x 32 chirps,
        500 particles and a coarse look-up table (for tests).

    Returns
    -------
    ScenarioConfig
    """
    lo, hi = (3.0, 5.0) if small else (3.0, 12.0)
    size = [float(rng.uniform(lo, hi)), float(rng.uniform(lo, hi)), float(rng.uniform(2.5, 4.0))]
    radius_m = float(rng.uniform(0.15, 0.3))
    for _ in range(100):
        boxes = _obstacles(rng, size, int(rng.integers(0, 3 if small else 4)))
        room = Room(np.asarray(size), tuple(Box(b["min"], b["max"]) for b in boxes))
        n_wp = int(rng.integers(3, 6) if small else rng.integers(5, 31))
        path = _path(rng, room, radius_m + PATH_MARGIN_M, n_wp, (0.3, 0.6) if small else (0.3, 1.5))
        if path is not None:
            break
    else:  # pragma: no cover - an empty room always has a path
        raise RuntimeError("random_scenario: no path found")
    heading = float(np.arctan2(*(path[1] - path[0])[::-1]))
    data: dict[str, Any] = {
        "name": f"random-{rng.integers(1 << 30):09d}",
        "description": "random_scenario draw",
        "room": {"size": size, "obstacles": boxes},
        "reflectors": _reflectors(rng, size, room),
        "radar": _radar(rng, size, small),
        "robot": {"start_pose": [*map(float, path[0]), heading], "radius_m": radius_m},
        "task": {"mode": "path", "path": path.tolist()},
    }
    if small:
        data["localization"] = {
            "initial_particles": 500,
            "min_particles": 100,
            "max_particles": 500,
            "lut_grid_m": 0.1,
            "lut_resolution_m": 0.1,
        }
    return ScenarioConfig.from_dict(data, data["name"])


def generated_room(
    seed: int, overrides: dict[str, Any] | None = None, *, small: bool = False
) -> ScenarioConfig:
    """Generated room ``seed`` (``random_scenario(default_rng(seed))``, what ``--random-rooms``
    runs) with the scenario ``overrides`` merged in."""
    cfg = random_scenario(np.random.default_rng(seed), small=small)
    return cfg.with_overrides(overrides) if overrides else cfg


def reflector_kinds(cfg: ScenarioConfig) -> str:
    """The reflector kinds a scenario's layout uses, sorted and joined by ``+``."""
    return "+".join(sorted({cfg.reflectors.types[r.type].kind for r in cfg.reflectors.layout}))


def random_perturbations(rng: np.random.Generator, share: float = 0.35) -> dict[str, Any]:
    """A ``perturbations`` section: each known perturbation on with probability ``share``, at
    a uniform severity (shadowing also with a random mode and count, kidnapping in a random
    frame window)."""
    out: dict[str, Any] = {}
    for name in PerturbationsConfig.model_fields:
        if rng.random() >= share:
            continue
        section: dict[str, Any] = {"severity": float(rng.uniform())}
        if name == "shadowing":
            section["mode"] = str(rng.choice(["static", "person"]))
            section["reflectors"] = int(rng.integers(1, 4))
        elif name == "kidnapping":
            section["frames"] = [int(rng.integers(0, 5)), int(rng.integers(5, 30))]
        out[name] = section
    return out


def _obstacles(rng: np.random.Generator, size: list[float], n: int) -> list[dict[str, Any]]:
    """``n`` boxes inside the room: footprints 0.3-1.5 m (at most a quarter side), 0.5-2 m tall."""
    out = []
    for i in range(n):
        wh = rng.uniform(0.3, np.minimum(1.5, np.asarray(size[:2]) / 4))
        x0 = rng.uniform(0.0, np.asarray(size[:2]) - wh)
        top = float(min(rng.uniform(0.5, 2.0), size[2]))
        out.append(
            {
                "min": [float(x0[0]), float(x0[1]), 0.0],
                "max": [float(x0[0] + wh[0]), float(x0[1] + wh[1]), top],
                "name": f"box{i}",
            }
        )
    return out


def _path(
    rng: np.random.Generator,
    room: Room,
    clearance_m: float,
    n_waypoints: int,
    step_m: tuple[float, float],
) -> np.ndarray | None:
    """A random walk of ``n_waypoints`` free waypoints with free legs, or None if stuck."""
    lo, hi = np.full(2, clearance_m), room.size_m[:2] - clearance_m
    if np.any(hi <= lo):
        return None
    cand = rng.uniform(lo, hi, size=(256, 2))
    cand = cand[room.free(cand, clearance_m)]
    if not len(cand):
        return None
    path = [cand[0]]
    while len(path) < n_waypoints:
        angle = rng.uniform(-np.pi, np.pi, 64)
        step = rng.uniform(*step_m, 64)
        nxt = path[-1] + step[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
        ok = room.legs_free(np.broadcast_to(path[-1], nxt.shape), nxt, clearance_m)
        if not ok.any():
            return None
        path.append(nxt[np.argmax(ok)])
    return np.round(np.asarray(path), 3)


def _reflector_type(rng: np.random.Generator, kind: str) -> dict[str, Any]:
    """Sizes of real reflectors of each kind at 60 GHz (a few cm to a few dm)."""
    if kind == "trihedral":
        return {"kind": kind, "edge_m": float(rng.uniform(0.03, 0.1))}
    if kind in ("sphere", "luneburg"):
        return {"kind": kind, "diameter_m": float(rng.uniform(0.05, 0.3))}
    if kind == "van_atta":
        return {
            "kind": kind,
            "elements": int(rng.integers(4, 17)),
            "element_area_m2": float(rng.uniform(1e-5, 1e-4)),
        }
    return {"kind": kind, "rcs_dbsm": float(rng.uniform(-10.0, 20.0))}


def _reflectors(rng: np.random.Generator, size: list[float], room: Room) -> dict[str, Any]:
    """1-3 used types of distinct kinds (plus, one time in five, an unused catalogue type)."""
    n_kinds = int(rng.integers(1, 4))
    extra = n_kinds < len(REFLECTOR_KINDS) and rng.random() < 0.2
    kinds = rng.choice(REFLECTOR_KINDS, n_kinds + int(extra), replace=False)
    types = {chr(ord("A") + i): _reflector_type(rng, str(k)) for i, k in enumerate(kinds)}
    n = int(rng.integers(3, 9))
    used = list(types)[:n_kinds]
    labels = used + [used[int(i)] for i in rng.integers(0, n_kinds, max(n - n_kinds, 0))]
    layout = []
    for label in labels:
        while True:
            p = rng.uniform([0.1, 0.1, 1.5], [size[0] - 0.1, size[1] - 0.1, size[2]])
            p = np.minimum(np.round(p, 3), size)  # rounding must not lift it above the ceiling
            if not any(bool(b.contains(p)) for b in room.obstacles):
                break
        layout.append({"position": [float(v) for v in p], "type": label})
    return {"types": types, "layout": layout}


def _radar(rng: np.random.Generator, size: list[float], small: bool) -> dict[str, Any]:
    """A waveform whose maximum range ``(N - 1) c / 2B`` covers the room's diagonal."""
    diag_m = float(np.linalg.norm(size))
    samples = [128, 256] if small else [128, 256, 512]
    n = int(rng.choice(samples))
    while (n - 1) * C_MPS / (2 * diag_m) < 0.5e9 * 1.01:  # no bandwidth >= 0.5 GHz fits
        n *= 2
    b_max = min(4e9, (n - 1) * C_MPS / (2 * diag_m) / 1.01)
    return {
        "bandwidth_hz": float(rng.uniform(0.5e9, b_max)),
        "samples_per_chirp": n,
        "chirps_per_frame": int(rng.choice([16, 32] if small else [16, 32, 64])),
        "mount_height_m": round(float(rng.uniform(0.2, 0.5)), 3),
    }
