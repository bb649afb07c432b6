"""``lrp-gym radar``: one radar frame at a pose, detections and true LRP distances."""

from __future__ import annotations

import numpy as np
import typer
from rich.table import Table

from lrp_gym.commands._common import ScenarioArg, console, print_json, save_figure
from lrp_gym.config import load_scenario
from lrp_gym.errors import InputError
from lrp_gym.world import World


def radar(
    scenario: str = typer.Argument(..., help=ScenarioArg),
    pose: tuple[float, float, float] = typer.Option(..., "--pose", help="X Y THETA (m, m, rad)."),
    velocity: float = typer.Option(0.0, "--velocity", help="Forward speed along THETA [m/s]."),
    seed: int = typer.Option(0, "--seed", help="Random seed (noise)."),
    plot: str | None = typer.Option(None, "--plot", help="Save the range-Doppler map (PNG)."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON only."),
) -> None:
    """Simulate one radar frame at --pose and print the detections and true LRP distances."""
    from lrp_gym.radar.sensor import RadarSensor

    if not np.isfinite(velocity):
        raise InputError(f"--velocity: must be a finite number, got {velocity:g}")
    cfg = load_scenario(scenario)
    world = World.from_config(cfg)
    p = np.asarray(pose, float)
    if not np.all(np.isfinite(p)) or not bool(world.room.free(p[:2])):
        raise InputError(
            f"--pose: position ({p[0]:g}, {p[1]:g}) is outside the room or inside an obstacle"
        )
    radar_cfg = cfg.radar.model_copy(update={"fidelity": "signal"})
    sensor = RadarSensor(world, radar_cfg)
    vel = velocity * np.array([np.cos(p[2]), np.sin(p[2])])
    det = sensor.measure(p, vel, np.random.default_rng(seed))
    true = world.true_distances_m(p[:2])
    if plot:
        from lrp_gym.radar.plotting import plot_range_doppler

        fig = plot_range_doppler(
            sensor.last_map_db,
            sensor.processor.range_axis_m,
            sensor.processor.velocity_axis_mps,
            det,
            true,
            title=f"{cfg.name} at ({p[0]:g}, {p[1]:g}, {p[2]:g})",
        )
        save_figure(fig, plot)
    if json_out:
        print_json(
            {
                "true_lrp_distances_m": true,
                "detections": [
                    {k: r[k] for k in ("range_m", "velocity_mps", "rcs_dbsm", "snr_db")}
                    for r in det.to_records()
                ],
            }
        )
        return
    table = Table(title=f"{len(det)} detections")
    for col in ("range [m]", "velocity [m/s]", "power [dBm]", "RCS [dBsm]", "SNR [dB]"):
        table.add_column(col, justify="right")
    for r in det.to_records():
        table.add_row(
            *(f"{r[k]:.3f}" for k in ("range_m", "velocity_mps")),
            *(f"{r[k]:.1f}" for k in ("power_dbm", "rcs_dbsm", "snr_db")),
        )
    console.print(table)
    console.print("true LRP distances (m): " + ", ".join(f"{d:.3f}" for d in true))
    if plot:
        console.print(f"saved {plot}")


def radar_rate(
    scenario: str = typer.Argument(..., help=ScenarioArg),
    poses: int = typer.Option(300, "--poses", min=1, help="Random free poses."),
    seed: int = typer.Option(0, "--seed", help="Seed of the poses and the noise."),
    fidelity: str = typer.Option("signal", "--fidelity", help="signal or detections."),
    json_out: bool = typer.Option(False, "--json", help="Print JSON only."),
) -> None:
    """How often each LRP is detected within 10 cm with an RCS inside the tracker's window."""
    from lrp_gym.radar.evaluate import lrp_detection_rate

    if fidelity not in ("signal", "detections"):
        raise InputError(f"--fidelity: expected signal or detections, got {fidelity!r}")
    cfg = load_scenario(scenario)
    res = lrp_detection_rate(cfg, poses, seed, fidelity=fidelity)
    if json_out:
        print_json({"scenario": cfg.name, "fidelity": fidelity, **res.as_dict()})
        return
    console.print(
        f"{cfg.name} ({fidelity}, {poses} poses): LRPs delivered {100 * res.rate:.1f} % "
        f"(within 10 cm: {100 * res.range_only_rate:.1f} %), "
        f"median RCS error {res.median_rcs_error_db:+.2f} dB, "
        f"range error std {100 * res.range_error_std_m:.2f} cm, "
        f"{res.mean_detections:.1f} detections/frame"
    )


def register(app: typer.Typer) -> None:
    app.command("radar")(radar)
    app.command("radar-rate")(radar_rate)
