"""Glue between scenarios and the placement tools: analyse a scenario, write a layout into it."""

from __future__ import annotations

import numpy as np

from lrp_gym.config import ReflectorTypeConfig, ScenarioConfig
from lrp_gym.placement.ambiguity import AmbiguityResult, analyse_layout
from lrp_gym.placement.grid import PositionGrid
from lrp_gym.world import World

#: The second type added by :func:`two_type_config`: a trihedral of 0.1 m edge, about
#: 12 dBsm at 60 GHz, 12 dB above the 0.05 m default type (easy to tell apart by RCS).
SECOND_TYPE = ReflectorTypeConfig(kind="trihedral", edge_m=0.1)


def tolerance_m(cfg: ScenarioConfig) -> float:
    """``placement.tolerance_m``, or the radar's range resolution when it is null."""
    tol = cfg.placement.tolerance_m
    return float(tol) if tol is not None else float(cfg.fmcw().range_resolution_m)


def layout_arrays(cfg: ScenarioConfig) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Reflector positions (M, 3), type indices (M,) and type names of a scenario."""
    names = tuple(cfg.reflectors.types)
    pos = np.array([r.position for r in cfg.reflectors.layout], dtype=float).reshape(-1, 3)
    idx = np.array([names.index(r.type) for r in cfg.reflectors.layout], dtype=int)
    return pos, idx, names


def analyse_scenario(cfg: ScenarioConfig, grid_m: float | None = None) -> AmbiguityResult:
    """Ambiguity map of a scenario's layout on its ``placement`` grid (or ``grid_m``)."""
    world = World.from_config(cfg)
    pc = cfg.placement
    grid = PositionGrid.from_room(world.room, grid_m or pc.grid_m, pc.clearance_m)
    pos, idx, _ = layout_arrays(cfg)
    return analyse_layout(
        pos,
        idx,
        grid,
        cfg.radar.mount_height_m,
        tolerance_m(cfg),
        pc.separation_m,
        lut_resolution_m=cfg.localization.lut_resolution_m,
        constraint_tolerance_m=pc.constraint_tolerance_m,
    )


def two_type_config(cfg: ScenarioConfig) -> ScenarioConfig:
    """The scenario with its reflectors split into two types, first half / second half.

    The first type is kept; a second type (:data:`SECOND_TYPE`, named ``"B"`` or the next free
    letter) is added when the scenario has only one.
    """
    data = cfg.to_dict()
    types = dict(data["reflectors"]["types"])
    names = list(types)
    if len(names) < 2:
        new = next(c for c in "BCDEFGHIJKLMNOPQRSTUVWXYZ" if c not in types)
        types[new] = SECOND_TYPE.model_dump(mode="json", exclude_none=True)
        names.append(new)
    layout = data["reflectors"]["layout"]
    half = len(layout) // 2
    for i, r in enumerate(layout):
        r["type"] = names[0] if i < half else names[1]
    data["reflectors"] = {"types": types, "layout": layout}
    return ScenarioConfig.from_dict(data, cfg.name)


def with_layout(cfg: ScenarioConfig, positions_m: np.ndarray) -> ScenarioConfig:
    """The scenario with new reflector positions (types and axes of the layout kept)."""
    data = cfg.to_dict()
    layout = data["reflectors"]["layout"]
    pos = np.asarray(positions_m, dtype=float).reshape(len(layout), 3)
    for r, p in zip(layout, pos, strict=True):
        r["position"] = [round(float(v), 3) for v in p]
    return ScenarioConfig.from_dict(data, cfg.name)
