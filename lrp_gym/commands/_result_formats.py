"""How the README's result rows state their numbers: one formatter and one target check per
kind of result (evaluation, reproduction, placement, benchmarks, trust, generated rooms)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

Data = dict[str, Any]  # key -> the row's stored JSON (its "result")

DET = ("--fidelity", "detections")


def _pct(x: float) -> str:
    return f"{100 * x:.0f} %"


def _eval(r: Any, _: Data) -> str:
    return (
        f"{_pct(r['success_rate'])} success, {_pct(r['collision_rate'])} collisions; loc. error "
        f"mean {r['mean_loc_error_m']:.3f} m, p95 {r['p95_loc_error_m']:.3f} m"
    )


def _repro(r: Any, _: Data) -> str:
    conv = r["amcl"]["converged_after"]
    worst = r["amcl"].get("worst_run_mean_error_m")
    worst_txt = f" (worst run {worst:.3f} m)" if worst is not None else ""
    return (
        f"AMCL {r['amcl']['mean_error_m']:.3f} m{worst_txt}, converged at position "
        f"{conv if conv is not None else 'never'} (paper: 0.097 m, 6); look-up table "
        f"{r['lut']['mean_error_m']:.2f} m, {r['lut']['entries']} entries (paper: 6574)"
    )


def _repro_met(limit_m: float) -> Callable[[Any, Data], bool]:
    def met(r: Any, _: Data) -> bool:
        conv = r["amcl"]["converged_after"]
        worst = r["amcl"].get("worst_run_mean_error_m", 0.0)
        return (
            r["amcl"]["mean_error_m"] <= limit_m
            and worst <= 0.08
            and conv is not None
            and conv <= 4
        )

    return met


def _cell(r: Any, name: str) -> dict:
    return next(c for c in r["cells"] if c["perturbation"] == name)


def _cells(r: Any, key: str, names: tuple[tuple[str, float], ...]) -> list[float]:
    return [
        next(c[key] for c in r["cells"] if (c["perturbation"], c["severity"]) == n) for n in names
    ]


def _placement(r: Any, _: Data) -> str:
    by = _by_method(r)
    return (
        f"{100 * np.mean(by['random']):.1f} % vs {100 * np.mean(by['optimize']):.1f} % "
        f"(mean of seeds 0-{len(by['random']) - 1}); optimiser better on "
        f"{sum(o < q for o, q in zip(by['optimize'], by['random'], strict=True))} of "
        f"{len(by['random'])}"
    )


def _by_method(r: Any) -> dict[str, list[float]]:
    out: dict[str, list[float]] = {"random": [], "optimize": []}
    for run in r:
        out[run["method"]].append(run["ambiguous_fraction"])
    return out


def _bench_load(r: Any) -> str:
    """Wall-clock speeds mean little on a busy machine: say how busy it was."""
    m = r.get("machine")
    if not m:
        return ""
    busy = m["load_avg_1min"] > 0.5 * m["cpus"]
    return f"; load {m['load_avg_1min']:.1f} on {m['cpus']} cores" + (
        ", not representative" if busy else ""
    )


def _trust(r: Any, _: Data) -> str:
    return (
        f"localised {100 * r['time_localised']:.1f} % of steps, confidently wrong "
        f"{100 * r['confidently_wrong_rate']:.1f} % of converged steps, median "
        f"{r['median_frames_to_localised']:g} frames to localised; {_pct(r['success_rate'])} success"
    )


def _trust_met(localised: float, wrong: float) -> Callable[[Any, Data], bool]:
    def met(r: Any, _: Data) -> bool:
        return (
            r["time_localised"] >= localised
            and r["confidently_wrong_rate"] <= wrong
            and r["median_frames_to_localised"] <= 4
        )

    return met


def _rooms(r: Any, _: Data) -> str:
    n = r["rooms"]
    k = round(r["share_amcl_radar_within_0_15_m"] * n)
    return (
        f"{k} of {n} rooms within 0.15 m; median AMCL error {r['median_amcl_radar_m']:.3f} m "
        f"(true fingerprints {r['median_amcl_true_m']:.3f} m)"
    )


def _rooms_trust(r: Any, _: Data) -> str:
    p = r["pooled"]
    return (
        f"confidently wrong {100 * p['confidently_wrong_rate']:.1f} % of converged steps "
        f"({r['wrong_converged_steps']} of {r['converged_steps']}); "
        f"{r['rooms_confidently_wrong_over_1pct']} of {r['rooms']} rooms over 1 %; localised "
        f"{100 * p['time_localised']:.1f} % of steps; {_pct(p['success_rate'])} success"
    )


def _trust_argv(scenario: str) -> tuple[str, ...]:
    return (
        "evaluate",
        scenario,
        "--agent",
        "pure-pursuit",
        "--task",
        "goal",
        *DET,
        "--episodes",
        "100",
        "--seed",
        "7000",
    )


def _vec(r: dict, fidelity: str) -> str:
    """``1.1x (44 vs 40 steps/s)``: the batched env at N = 64 against the single env."""
    v = r["vector"][fidelity]
    n64 = v["N=64"]
    return (
        f"{n64['speedup_vs_single']:.1f}x ({n64['steps_per_s']:.0f} vs "
        f"{v['single_env_steps_per_s']:.0f} steps/s)"
    )
