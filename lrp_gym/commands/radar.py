"""``lrp-gym radar`` and ``radar-rate``: one radar frame at a pose; LRP delivery rates."""

from __future__ import annotations

import numpy as np
import typer

from lrp_gym.commands._common import (
    FIDELITIES,
    at_least,
    check_distinct,
    check_output,
    choice,
    console,
    fidelity_option,
    force_option,
    json_option,
    load_config,
    out_option,
    plot_option,
    print_json,
    save_figure,
    scenario_argument,
    seed_option,
    sets_option,
    table,
    write_json,
    wrote,
)
from lrp_gym.errors import InputError
from lrp_gym.world import World

DETECTION_KEYS = ("range_m", "velocity_mps", "power_dbm", "rcs_dbsm", "snr_db")


def radar(
    scenario: str = scenario_argument(),
    pose: tuple[float, float, float] = typer.Option(
        ..., "--pose", metavar="X Y THETA", help="Radar pose: x [m], y [m], heading [rad]."
    ),
    velocity: float = typer.Option(
        0.0, "--velocity", metavar="M_PER_S", help="Forward speed along THETA [m/s]."
    ),
    seed: int = seed_option("Seed of the thermal noise."),
    sets: list[str] = sets_option(),
    out: str | None = out_option("the detections and true distances as JSON"),
    plot: str | None = plot_option("the range-Doppler map"),
    force: bool = force_option(),
    json_out: bool = json_option("the detections and true distances"),
) -> None:
    """Simulate one signal-level radar frame at --pose.

    Prints the detections (range, radial velocity, power, RCS, SNR) and the true distances to
    the LRPs.
    """
    from lrp_gym.radar.sensor import RadarSensor

    at_least(velocity, -float("inf"), "--velocity")
    out_path = check_output(out, "--out", force, (".json",))
    plot_path = check_output(plot, "--plot", force, (".png", ".pdf", ".svg"))
    check_distinct(out_path, plot_path)
    cfg = load_config(scenario, sets)
    world = World.from_config(cfg)
    p = np.asarray(pose, float)
    if not np.all(np.isfinite(p)) or not bool(world.room.free(p[:2])):
        raise InputError(
            f"--pose: position ({p[0]:g}, {p[1]:g}) is outside the room or inside an obstacle"
        )
    sensor = RadarSensor(world, cfg.radar.model_copy(update={"fidelity": "signal"}))
    vel = velocity * np.array([np.cos(p[2]), np.sin(p[2])])
    det = sensor.measure(p, vel, np.random.default_rng(seed))
    true = world.true_distances_m(p[:2])
    if plot_path is not None:
        from lrp_gym.radar.plotting import plot_range_doppler

        map_db = sensor.last_map_db
        if map_db is None:  # the signal fidelity keeps its map
            raise InputError("--plot: the range-Doppler map needs --fidelity signal")
        fig = plot_range_doppler(
            map_db,
            sensor.processor.range_axis_m,
            sensor.processor.velocity_axis_mps,
            det,
            true,
            title=f"{cfg.name} at ({p[0]:g} m, {p[1]:g} m, {p[2]:g} rad)",
        )
        save_figure(fig, plot_path)
    records = [{k: r[k] for k in DETECTION_KEYS} for r in det.to_records()]
    doc = {"true_lrp_distances_m": true, "detections": records}
    if out_path is not None:
        write_json(doc, out_path)
    if json_out:
        print_json(doc)
    else:
        _print_frame(det, records, true)
    for path in (plot_path, out_path):
        if path is not None:
            wrote(path, quiet=json_out)


def _print_frame(det, records: list[dict], true: np.ndarray) -> None:
    cols = ("range [m]", "velocity [m/s]", "power [dBm]", "RCS [dBsm]", "SNR [dB]")
    t = table(f"{len(det)} detections", cols)
    for r in records:
        t.add_row(
            *(f"{r[k]:.3f}" for k in DETECTION_KEYS[:2]),
            *(f"{r[k]:.1f}" for k in DETECTION_KEYS[2:]),
        )
    console.print(t)
    console.print("true LRP distances [m]: " + ", ".join(f"{d:.3f}" for d in true), markup=False)


def radar_rate(
    scenario: str = scenario_argument(),
    poses: int = typer.Option(300, "--poses", metavar="N", help="Random free poses (>= 1)."),
    seed: int = seed_option("Seed of the poses and the noise."),
    fidelity: str | None = fidelity_option(),
    sets: list[str] = sets_option(),
    out: str | None = out_option("the rates as JSON"),
    force: bool = force_option(),
    json_out: bool = json_option(),
) -> None:
    """How often the radar delivers each LRP: detected within 10 cm with an RCS inside the
    tracker's window, per LRP and in total."""
    from lrp_gym.radar.delivery_rate import lrp_detection_rate

    if poses < 1:
        raise InputError(f"--poses: must be at least 1, got {poses}")
    choice(fidelity, FIDELITIES, "--fidelity")
    out_path = check_output(out, "--out", force, (".json",))
    cfg = load_config(scenario, sets, fidelity)
    res = lrp_detection_rate(cfg, poses, seed)
    fid = cfg.radar.fidelity
    doc = {"scenario": cfg.name, "fidelity": fid, **res.as_dict()}
    if out_path is not None:
        write_json(doc, out_path)
    if json_out:
        print_json(doc)
        if out_path is not None:
            wrote(out_path, quiet=True)
        return
    console.print(f"{cfg.name}, {fid} radar, {poses} poses, seed {seed}:", markup=False)
    t = table("delivered per LRP", ("LRP", "type", "delivered", "when in view"))
    rates = zip(cfg.reflectors.layout, res.per_lrp_rate, res.per_lrp_in_view_rate, strict=True)
    for i, (r, rate, seen) in enumerate(rates):
        t.add_row(f"#{i}", r.type, f"{100 * rate:.1f} %", f"{100 * seen:.1f} %")
    console.print(t)
    console.print(
        f"all LRPs: delivered {100 * res.rate:.1f} % (within 10 cm: "
        f"{100 * res.range_only_rate:.1f} %), median RCS error {res.median_rcs_error_db:+.2f} dB, "
        f"range error std {100 * res.range_error_std_m:.2f} cm, "
        f"{res.mean_detections:.1f} detections/frame",
        markup=False,
    )
    console.print(
        f"when in view: delivered {100 * res.in_view_rate:.1f} % (the likelihood assumes "
        f"localization.detection_probability = {100 * cfg.localization.detection_probability:.0f} %)",
        markup=False,
    )
    if out_path is not None:
        wrote(out_path)


def register(app: typer.Typer) -> None:
    app.command("radar", short_help="One radar frame at a pose: detections, true distances.")(radar)
    app.command("radar-rate", short_help="How often the radar delivers each LRP.")(radar_rate)
