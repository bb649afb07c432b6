"""``lrp-gym validate``: check a scenario and print what follows from it."""

from __future__ import annotations

import numpy as np
import typer
from rich.table import Table

from lrp_gym.commands._common import ScenarioArg, SetHelp, console, parse_sets, print_json
from lrp_gym.config import load_scenario
from lrp_gym.world import World


def validate(
    scenario: str = typer.Argument(..., help=ScenarioArg),
    json_out: bool = typer.Option(False, "--json", help="Print the derived numbers as JSON."),
    sets: list[str] = typer.Option(None, "--set", help=SetHelp),
) -> None:
    """Validate SCENARIO and print the room, the reflectors and the derived radar numbers.

    Invalid scenarios print one line per problem, naming the field, and exit with code 2.
    """
    cfg = load_scenario(scenario).with_overrides(parse_sets(sets, scenario))
    world = World.from_config(cfg)
    fm = world.fmcw
    if json_out:
        print_json(
            {
                "name": cfg.name,
                "room_size_m": cfg.room.size,
                "obstacles": len(cfg.room.obstacles),
                "reflectors": [
                    {"position_m": r.position, "type": r.type} for r in cfg.reflectors.layout
                ],
                "reflector_types": {
                    t.name: {"kind": t.kind, "rcs_dbsm": t.rcs_dbsm} for t in world.layout.types
                },
                "radar": fm.summary(),
                "valid": True,
            }
        )
        return
    console.print(f"[bold green]valid[/] scenario [bold]{cfg.name}[/]  {cfg.description}")
    lx, ly, lz = cfg.room.size
    console.print(
        f"room {lx:g} x {ly:g} x {lz:g} m, {len(cfg.room.obstacles)} obstacles, "
        f"diagonal {world.room.diagonal_m:.3f} m"
    )
    refl = Table(title="reflectors", show_lines=False)
    for col in ("#", "type", "kind", "x [m]", "y [m]", "z [m]", "RCS [dBsm]"):
        refl.add_column(col, justify="right")
    for i, (pos, t) in enumerate(
        zip(world.layout.positions_m, world.layout.type_index, strict=True)
    ):
        rt = world.layout.types[t]
        refl.add_row(str(i), rt.name, rt.kind, *(f"{v:.3f}" for v in pos), f"{rt.rcs_dbsm:.2f}")
    console.print(refl)
    radar = Table(title="radar (derived)")
    radar.add_column("quantity")
    radar.add_column("value", justify="right")
    rows = [
        ("carrier", f"{fm.carrier_hz / 1e9:.3f} GHz (lambda {fm.wavelength_m * 1e3:.3f} mm)"),
        ("bandwidth", f"{fm.bandwidth_hz / 1e9:.4f} GHz"),
        ("chirp period", f"{fm.chirp_period_s * 1e6:.2f} us"),
        ("samples x chirps", f"{fm.samples_per_chirp} x {fm.chirps_per_frame}"),
        ("sample rate", f"{fm.sample_rate_hz / 1e6:.4f} MHz"),
        ("range resolution", f"{fm.range_resolution_m:.4f} m"),
        ("maximum range", f"{fm.max_range_m:.3f} m"),
        ("velocity resolution", f"{fm.velocity_resolution_mps:.4f} m/s"),
        ("velocity span", f"+-{fm.max_velocity_mps:.4f} m/s"),
        ("frame time", f"{fm.frame_time_s * 1e3:.3f} ms"),
        ("mount height", f"{cfg.radar.mount_height_m:g} m"),
    ]
    for k, v in rows:
        radar.add_row(k, v)
    console.print(radar)
    if cfg.task.mode == "path":
        path = np.asarray(cfg.task.path)
        length = float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)))
        console.print(f"task: follow a {len(path)}-waypoint path, {length:.2f} m long")
    else:
        console.print("task: sampled start poses and goals")


def register(app: typer.Typer) -> None:
    app.command("validate")(validate)
