"""``lrp-gym validate``: check a scenario and print what follows from it."""

from __future__ import annotations

import numpy as np
import typer

from lrp_gym.commands._common import (
    check_output,
    console,
    force_option,
    json_option,
    load_config,
    out_option,
    print_json,
    scenario_argument,
    sets_option,
    table,
    write_json,
    wrote,
)
from lrp_gym.world import World


def validate(
    scenario: str = scenario_argument(),
    sets: list[str] = sets_option(),
    out: str | None = out_option("the derived numbers as JSON"),
    force: bool = force_option(),
    json_out: bool = json_option("the derived numbers"),
) -> None:
    """Validate SCENARIO and print the room, the reflectors and the derived radar numbers.

    Invalid scenarios print one line per problem, naming the field, and exit with code 2.
    """
    out_path = check_output(out, "--out", force, (".json",))
    cfg = load_config(scenario, sets)
    world = World.from_config(cfg)
    if out_path is not None:
        write_json(_as_dict(cfg, world), out_path)
    if json_out:
        print_json(_as_dict(cfg, world))
        if out_path is not None:
            wrote(out_path, quiet=True)
        return
    console.print(f"[bold green]valid[/] scenario [bold]{cfg.name}[/]  {cfg.description}")
    lx, ly, lz = cfg.room.size
    console.print(
        f"room {lx:g} x {ly:g} x {lz:g} m, {len(cfg.room.obstacles)} obstacles, "
        f"diagonal {world.room.diagonal_m:.3f} m"
    )
    cols = ("#", "type", "kind", "x [m]", "y [m]", "z [m]", "RCS [dBsm]")
    refl = table("reflectors", cols)
    for i, (pos, t) in enumerate(
        zip(world.layout.positions_m, world.layout.type_index, strict=True)
    ):
        rt = world.layout.types[t]
        refl.add_row(str(i), rt.name, rt.kind, *(f"{v:.3f}" for v in pos), f"{rt.rcs_dbsm:.2f}")
    console.print(refl)
    radar = table("radar (derived)", ("quantity", "value"), left=1)
    for k, v in _radar_rows(cfg, world.fmcw):
        radar.add_row(k, v)
    console.print(radar)
    if cfg.task.mode == "path":
        path = np.asarray(cfg.task.path)
        length = float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)))
        console.print(f"task: follow a {len(path)}-waypoint path, {length:.2f} m long")
    else:
        console.print("task: sampled start poses and goals")
    if out_path is not None:
        wrote(out_path)


def _as_dict(cfg, world: World) -> dict:
    return {
        "name": cfg.name,
        "room_size_m": cfg.room.size,
        "obstacles": len(cfg.room.obstacles),
        "reflectors": [{"position_m": r.position, "type": r.type} for r in cfg.reflectors.layout],
        "reflector_types": {
            t.name: {"kind": t.kind, "rcs_dbsm": t.rcs_dbsm} for t in world.layout.types
        },
        "radar": world.fmcw.summary(),
        "valid": True,
    }


def _radar_rows(cfg, fm) -> list[tuple[str, str]]:
    return [
        ("carrier", f"{fm.carrier_hz / 1e9:.3f} GHz (lambda {fm.wavelength_m * 1e3:.3f} mm)"),
        ("bandwidth", f"{fm.bandwidth_hz / 1e9:.4f} GHz"),
        ("chirp period", f"{fm.chirp_period_s * 1e6:.2f} us"),
        ("samples x chirps", f"{fm.samples_per_chirp} x {fm.chirps_per_frame}"),
        ("sample rate", f"{fm.sample_rate_hz / 1e6:.4f} MHz"),
        ("range resolution", f"{fm.range_resolution_m:.4f} m"),
        ("maximum range", f"{fm.max_range_m:.3f} m"),
        ("velocity resolution", f"{fm.velocity_resolution_mps:.4f} m/s"),
        ("velocity span", f"±{fm.max_velocity_mps:.4f} m/s"),
        ("frame time", f"{fm.frame_time_s * 1e3:.3f} ms"),
        ("mount height", f"{cfg.radar.mount_height_m:g} m"),
    ]


def register(app: typer.Typer) -> None:
    app.command("validate", short_help="Check a scenario; print room, reflectors, radar.")(validate)
