"""The README's results table: one row per command whose JSON is kept in docs/results.

Each row names the ``lrp-gym`` arguments that print its JSON (``--json``; a row may run several
commands, e.g. one per seed and method, and then stores the list of their results), how to
state the measured value, and, when it has a target, the comparison that decides "missed".
A row too slow to rerun here may read its numbers from a file its own command writes
(``source``, e.g. the training run's model card). Rows with neither keep their typed text,
marked "(not regenerated)".
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from lrp_gym.commands._result_formats import (
    DET,
    _bench_load,
    _by_method,
    _cells,
    _eval,
    _pct,
    _placement,
    _repro,
    _repro_met,
    _rooms,
    _rooms_trust,
    _trust,
    _trust_argv,
    _trust_met,
    _vec,
)
from lrp_gym.config import CONFIGS_DIR

ROOT = CONFIGS_DIR.parent
RESULTS_DIR = ROOT / "docs" / "results"
README = ROOT / "README.md"
START, END = "<!-- results:start (lrp-gym report) -->", "<!-- results:end -->"

Data = dict[str, Any]  # key -> the row's stored JSON (its "result")


@dataclass(frozen=True)
class Row:
    """One line of the table.

    ``argv`` (one command) or ``runs`` (several) are what ``lrp-gym report --rerun`` runs;
    with neither, the row is not rerun and its numbers come from ``source`` if given.
    """

    key: str
    what: str
    target: str
    argv: tuple[str, ...] | None
    measured: Callable[[Any, Data], str] | None = None
    met: Callable[[Any, Data], bool] | None = None
    typed: str = ""
    command: str = ""
    runs: tuple[tuple[str, ...], ...] = ()
    source: Path | None = None

    @property
    def commands(self) -> tuple[tuple[str, ...], ...]:
        """The argument lists ``lrp-gym report --rerun`` runs for this row (may be empty)."""
        return (self.argv,) if self.argv is not None else self.runs

    @property
    def shown_command(self) -> str:
        return self.command or "lrp-gym " + " ".join(self.argv or ())


PLACEMENT_SEEDS = range(5)
ROBUST = (("shadowing", 0.25), ("missed_detections", 0.2))
KIDNAP = (("kidnapping", 0.5), ("kidnapping", 1.0))

#: How a training run's ``n_envs`` envs ran (``vec_env`` in its config).
VEC_ENV_WORDS = {
    "batch": "robots in one batched env",
    "subproc": "subprocess envs",
    "dummy": "envs in turn",
    None: "envs",
}

ROWS: tuple[Row, ...] = (
    Row(
        "trust_1type",
        "unknown start pose and heading (the env's default task), 1-type paper room, pure "
        "pursuit, detections fidelity, 100 episodes",
        "localised >= 90 %, confidently wrong <= 1 %, median frames <= 4",
        _trust_argv("ipin2023"),
        _trust,
        _trust_met(0.90, 0.01),
    ),
    Row(
        "trust_2types",
        "same on the 2 + 2 layout",
        "localised >= 97 %, confidently wrong <= 0.5 %",
        _trust_argv("ipin2023-2types"),
        _trust,
        _trust_met(0.97, 0.005),
    ),
    Row(
        "rooms_trust",
        "unknown start pose and heading (the default task) on 20 generated rooms, pure "
        "pursuit, detections fidelity, 20 episodes each",
        "confidently wrong <= 1 % (pooled)",
        (
            "evaluate",
            "--random-rooms",
            "20",
            "--agent",
            "pure-pursuit",
            "--task",
            "goal",
            *DET,
            "--episodes",
            "20",
            "--seed",
            "7000",
        ),  # fmt: skip
        _rooms_trust,
        lambda r, _: r["pooled"]["confidently_wrong_rate"] <= 0.01,
    ),
    Row(
        "random_rooms",
        "AMCL on 20 generated rooms (random sizes, obstacles, reflector kinds), radar chain",
        ">= 75 % of rooms within 0.15 m",
        ("reproduce-paper", "--random-rooms", "20", "--runs", "1"),
        _rooms,
        lambda r, _: r["share_amcl_radar_within_0_15_m"] >= 0.75,
    ),
    Row(
        "radar_rate",
        "LRPs delivered by the signal chain (within 10 cm, RCS in window), paper room, noise on",
        "-",
        ("radar-rate", "--poses", "500", "--seed", "0"),
        lambda r, _: (
            f"{100 * r['rate']:.1f} % (median RCS error {r['median_rcs_error_db']:+.1f} dB, "
            f"range std {100 * r['range_error_std_m']:.1f} cm)"
        ),
        typed="94.8 % (median RCS error -0.8 dB, range std 2.6 cm)",
    ),
    Row(
        "reproduce_noise_off",
        "paper path, 15 positions, noise off (10 runs)",
        "AMCL <= 0.05 m, every run <= 0.08 m, converged <= 4",
        ("reproduce-paper", "--runs", "10", "--no-noise"),
        _repro,
        _repro_met(0.05),
        typed="AMCL 0.095 m, converged at position 6 (missed)",
    ),
    Row(
        "reproduce_noise_on",
        "paper path, 15 positions, noise on (10 runs)",
        "AMCL <= 0.05 m, every run <= 0.08 m, converged <= 4",
        ("reproduce-paper", "--runs", "10", "--noise"),
        _repro,
        _repro_met(0.05),
        typed="AMCL 0.084 m, converged at position 5 (missed)",
    ),
    Row(
        "reproduce_best_k",
        "same with the paper's estimator rule (20 best particles), noise on",
        "-",
        ("reproduce-paper", "--runs", "10", "--noise", "--estimator", "best_k"),
        _repro,
        typed="AMCL 0.235 m; 0.053 m from position 3",
    ),
    Row(
        "track_seed0",
        "tracked fingerprint vs truth on the paper path, 15 frames, seed 0",
        "-",
        ("track", "--seed", "0"),
        lambda r, _: (
            f"tracked RMSE {r['tracked_rmse_m']:.3f} m (raw detections {r['raw_rmse_m']:.3f} m), "
            f"swaps: {r['swaps']}; seeds 0-4: see [docs/tracking.md](docs/tracking.md)"
        ),
        typed="0.086 m over seeds 0-4 (0.076-0.129), 1-6 swaps",
    ),
    Row(
        "layout_random",
        "layout search, 500 candidates",
        "<= 20 s",
        ("layout", "--candidates", "500", "--seed", "0"),
        lambda r, _: f"{r['search_s']:.1f} s; ambiguous {100 * r['ambiguous_fraction']:.1f} %",
        lambda r, _: r["search_s"] <= 20.0,
        typed="4.0-4.4 s",
    ),
    Row(
        "placement_methods",
        "ambiguous area: random search vs differential evolution (5 seeds, 1 type)",
        "optimiser wins",
        None,
        _placement,
        lambda r, _: np.mean(_by_method(r)["optimize"]) < np.mean(_by_method(r)["random"]),
        typed="13.4 % vs 9.0 %",
        command="lrp-gym layout --candidates 500 --types 1 --method random|optimize --seed 0..4",
        runs=tuple(
            ("layout", "--candidates", "500", "--types", "1", "--method", m, "--seed", str(s))
            for s in PLACEMENT_SEEDS
            for m in ("random", "optimize")
        ),
    ),
    Row(
        "pp_path",
        "pure pursuit on the paper path (`LRPRadarNav-v0`, 20 episodes)",
        "100 %, p95 loc. error <= 0.10 m",
        ("evaluate", "--agent", "pure-pursuit", "--episodes", "20", "--seed", "0"),
        _eval,
        lambda r, _: r["success_rate"] >= 1.0 and r["p95_loc_error_m"] <= 0.10,
        typed="100 %, mean 0.041 m, p95 0.095 m",
    ),
    Row(
        "pp_goal",
        "pure pursuit, sampled goals (`LRPRadarNav-v0`, 50 episodes)",
        "-",
        (
            "evaluate",
            "--agent",
            "pure-pursuit",
            "--task",
            "goal",
            "--episodes",
            "50",
            "--seed",
            "1000",
        ),
        _eval,
        typed="92 % success, 4 % collisions; loc. error mean 1.83 m, p95 5.4 m",
    ),
    Row(
        "ppo_goal",
        "shipped PPO, sampled goals (`LRPRadarNav-v0`, same 50 seeds)",
        ">= 90 %, within 10 points of PP",
        ("evaluate", "--agent", "ppo", "--task", "goal", "--episodes", "50", "--seed", "1000"),
        _eval,
        lambda r, d: (
            r["success_rate"] >= 0.9
            and ("pp_goal" not in d or r["success_rate"] >= d["pp_goal"]["success_rate"] - 0.1)
        ),
        typed="94 % success (PP: 92 %); loc. error mean 0.23 m",
    ),
    Row(
        "ppo_training",
        "PPO training wall time (shipped model; not rerun by `lrp-gym report`)",
        "<= 30 min",
        None,
        lambda r, _: (
            f"{r['wall_time_s'] / 60:.1f} min for {r['timesteps']:,} steps "
            f"({r['hyperparams']['n_envs']} {VEC_ENV_WORDS[r['hyperparams'].get('vec_env')]}; "
            "from agents/models/ppo_lrp_nav.json)"
        ),
        lambda r, _: r["wall_time_s"] <= 30 * 60,
        typed="19.6 min for 300k steps (2 subprocess envs)",
        command="lrp-gym train --out runs/ppo-main --seed 0 --export agents/models",
        source=ROOT / "agents" / "models" / "ppo_lrp_nav.json",
    ),
    Row(
        "bench_radar",
        "radar signal chain (channel + cube + FFT + CFAR), one core",
        ">= 1000 frames/s",
        ("bench", "-c", "radar"),
        lambda r, _: (
            f"{r['radar_frames_per_s']:.0f} frames/s; detections fidelity "
            f"{r['radar_fast_frames_per_s']:.0f}{_bench_load(r)}"
        ),
        lambda r, _: r["radar_frames_per_s"] >= 1000,
        typed="935-1037 frames/s over two runs; detections fidelity 1850 (missed on one run)",
    ),
    Row(
        "bench_amcl",
        "AMCL update, 10000 particles / converged count",
        "<= 1.5 / 0.3 ms",
        ("bench", "-c", "amcl"),
        lambda r, _: (
            f"{r['amcl_update_ms_10000']:.1f} / {r['amcl_update_ms_converged']:.2f} ms "
            f"({r['amcl_converged_particles']} particles){_bench_load(r)}"
        ),
        lambda r, _: r["amcl_update_ms_10000"] <= 1.5 and r["amcl_update_ms_converged"] <= 0.3,
        typed="3.6 / 1.3 ms (missed; 1.1 / 0.42 ms without the structure term)",
    ),
    Row(
        "bench_env",
        "`LRPRadarNav-v0` / `LRPRadarNavFast-v0` steps/s (converged)",
        ">= 500 / 3000",
        ("bench", "-c", "env"),
        lambda r, _: (
            f"{r['variants']['LRPRadarNav-v0']['steps_per_s']:.0f} / "
            f"{r['variants']['LRPRadarNavFast-v0']['steps_per_s']:.0f}{_bench_load(r)}"
        ),
        lambda r, _: (
            r["variants"]["LRPRadarNav-v0"]["steps_per_s"] >= 500
            and r["variants"]["LRPRadarNavFast-v0"]["steps_per_s"] >= 3000
        ),
        typed="440 / 510-520 (missed)",
    ),
    Row(
        "bench_vector",
        "batched env (`gym.make_vec`, N = 64) against the single env, steps/s per core, "
        "detections / signal fidelity",
        ">= 10x / >= 4x",
        ("bench", "-c", "vector"),
        lambda r, _: (
            f"{_vec(r, 'detections')} / {_vec(r, 'signal')}; peak memory "
            f"{r['vector']['peak_rss_mb']:.0f} MB with N = 256{_bench_load(r)}"
        ),
        lambda r, _: (
            r["vector"]["detections"]["N=64"]["speedup_vs_single"] >= 10
            and r["vector"]["signal"]["N=64"]["speedup_vs_single"] >= 4
        ),
    ),
    Row(
        "robustness_shadowing_missed",
        "robustness: shadowing 10 frames / 20 % missed detections, PP success (paper path, "
        "detections fidelity, 20 episodes)",
        ">= 95 %",
        (
            "robustness",
            *DET,
            "--episodes",
            "20",
            "--perturbations",
            "shadowing,missed_detections",
            "--severities",
            "0.25,0.2",
        ),
        lambda r, _: " / ".join(_pct(v) for v in _cells(r, "success_rate", ROBUST)),
        lambda r, _: min(_cells(r, "success_rate", ROBUST)) >= 0.95,
        typed="100 % / 75 % (missed)",
    ),
    Row(
        "robustness_kidnapping",
        "kidnapping: recovered (< 0.2 m) within 15 frames, jump >= 1.5 m / >= 3 m (oracle "
        "driver, detections fidelity, 20 episodes)",
        ">= 90 %",
        (
            "robustness",
            "--agent",
            "oracle",
            *DET,
            "--episodes",
            "20",
            "--perturbations",
            "kidnapping",
            "--severities",
            "0.5,1",
        ),
        lambda r, _: " / ".join(_pct(v) for v in _cells(r, "recovered_within_budget", KIDNAP)),
        lambda r, _: min(_cells(r, "recovered_within_budget", KIDNAP)) >= 0.9,
        typed="55 % / 60 % (missed)",
    ),
)


def load_results(directory: Path = RESULTS_DIR) -> Data:
    """The stored ``result`` of every row that has a JSON file."""
    out: Data = {}
    for row in ROWS:
        f = directory / f"{row.key}.json"
        if f.is_file():
            out[row.key] = json.loads(f.read_text(encoding="utf-8"))["result"]
        elif row.source is not None and row.source.is_file():
            out[row.key] = json.loads(row.source.read_text(encoding="utf-8"))
    return out


def render_row(row: Row, data: Data) -> str:
    """One markdown line; 'missed' and 'not regenerated' come from here only."""
    if row.key in data and row.measured is not None:
        text = row.measured(data[row.key], data)
        if row.met is not None and not row.met(data[row.key], data):
            text += " (missed)"
    else:
        text = f"{row.typed} (not regenerated)"
    cmd = row.shown_command
    cmd = cmd if cmd.startswith("see ") else f"`{cmd}`"
    return f"| {row.what} | {row.target} | {text} | {cmd} |"


def render_table(data: Data) -> str:
    """The whole table (header and rows)."""
    lines = ["| what | target | measured | command |", "|---|---|---|---|"]
    return "\n".join(lines + [render_row(r, data) for r in ROWS])


def replace_table(readme: str, table: str) -> str:
    """``readme`` with the text between the markers replaced by ``table``."""
    head, sep, rest = readme.partition(START)
    _, sep2, tail = rest.partition(END)
    if not (sep and sep2):
        raise ValueError(f"README.md lacks the markers {START} ... {END}")
    return f"{head}{START}\n{table}\n{END}{tail}"
