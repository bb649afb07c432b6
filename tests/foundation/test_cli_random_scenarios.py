"""Every valid scenario runs through every scenario command of the CLI.

Users write their own scenario YAML and run the commands on it. Here random draws of
:func:`~lrp_gym.experiments.scenarios.random_scenario` (``small=True``; odd seeds with a
random ``perturbations`` section) are written with :func:`~lrp_gym.config.save_scenario` and
every command that takes a scenario runs on the file in-process (``lrp_gym.cli.main``, as in
test_cli_grammar.py) with its cheapest options; ``train`` and ``sweep`` (PPO) are left out.
Each must exit 0, and its ``--json`` must be strict JSON (no NaN or Infinity: non-finite
numbers are ``null``) whose figures agree with the scenario and the options.

One failure is accepted, the documented one (docs/scenarios.md, "CLI fuzz"): ``layout`` exits
2 with its one-line ``placement: only k of n random layouts ... are feasible; relax ...``
when hardly any layout of the scenario's reflectors keeps the spacing and the symmetry
constraint in the room (many reflectors of one type in a small room).

A small hypothesis draw runs in the default suite; the seed sweep, with plots, GIF, the other
layout methods, the grid localiser and the other bench components on top, is marked slow::

    .venv/bin/python -m pytest -m slow tests/foundation/test_cli_random_scenarios.py
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lrp_gym.cli import main
from lrp_gym.config import ScenarioConfig, save_scenario
from lrp_gym.experiments.scenarios import random_perturbations, random_scenario
from lrp_gym.perturbations import NAMES

#: The one accepted failure: no feasible layout for the search to start from.
INFEASIBLE_LAYOUT = re.compile(
    r"error: placement: only \d+ of \d+ random layouts in \d+ draws are feasible; relax "
    r"placement\.min_spacing_m, wall_distance_m or constraint_tolerance_m"
)

Check = Callable[[dict], None]


def _no_constant(name: str) -> None:
    raise AssertionError(f"--json printed {name}; non-finite numbers must be null")


def _leaves(value):
    if isinstance(value, dict):
        for v in value.values():
            yield from _leaves(v)
    elif isinstance(value, list):
        for v in value:
            yield from _leaves(v)
    else:
        yield value


def _share(x) -> bool:
    return x is None or 0.0 <= x <= 1.0


def write_draw(seed: int, folder: Path) -> tuple[Path, ScenarioConfig, np.random.Generator]:
    """Scenario draw ``seed`` as a YAML file in ``folder``; the generator goes on for options."""
    rng = np.random.default_rng(seed)
    data = random_scenario(rng, small=True).to_dict()
    if seed % 2:
        data["perturbations"] = random_perturbations(rng)
    cfg = ScenarioConfig.from_dict(data, f"draw {seed}")
    folder.mkdir(parents=True, exist_ok=True)
    return save_scenario(cfg, folder / "scenario.yaml"), cfg, rng


def core_cases(
    path: Path, cfg: ScenarioConfig, rng: np.random.Generator
) -> list[tuple[list[str], Check]]:
    """Every scenario command once, cheapest options, with a check of its JSON."""
    p, n = str(path), len(cfg.reflectors.layout)
    pose = [str(v) for v in cfg.robot.start_pose]
    fid = [str(f) for f in rng.choice(["signal", "detections"], 3)]
    pert = str(rng.choice(NAMES))
    out = path.parent

    def validate(d):
        assert d["valid"] is True and d["name"] == cfg.name and len(d["reflectors"]) == n

    def radar(d):
        assert len(d["true_lrp_distances_m"]) == n and min(d["true_lrp_distances_m"]) > 0
        assert all(det["range_m"] is not None and det["range_m"] >= 0 for det in d["detections"])

    def rate(d):
        assert d["n_poses"] == 3 and d["n_lrps"] == n and len(d["per_lrp_rate"]) == n
        assert all(map(_share, [d["rate"], d["in_view_rate"], *d["per_lrp_rate"]]))

    def track(d):
        assert d["frames"] >= 1 and d["swaps"] >= 0 and 0 <= d["missed_frames"] <= d["frames"]

    def reproduce(d):
        errors = [*d["lut"]["errors_m"], *d["amcl"]["mean_errors_m"]]
        assert d["runs"] == 1 and d["positions"] >= 1 and len(errors) == 2 * d["positions"]
        assert all(e is not None and e >= 0 for e in errors)

    def layout(d):
        assert len(d["layout"]) == n and d["evaluations"] == 2
        assert _share(d["ambiguous_fraction"]) and d["ambiguous_fraction"] is not None

    def ambiguity(d):
        assert d["grid_m"] == 0.2 and d["cells"] >= 1
        fractions = [d[k] for k in ("ambiguous_fraction", "systematic_fraction")]
        assert all(f is not None and _share(f) for f in fractions)

    def evaluate(task, fidelity, episodes):
        def check(d):
            assert (d["task"], d["fidelity"], d["episodes"]) == (task, fidelity, episodes)
            assert _share(d["success_rate"]) and _share(d["collision_rate"])
            assert d["mean_steps"] >= 1

        return check

    def robustness(d):
        assert [(c["perturbation"], c["episodes"]) for c in d["cells"]] == [("none", 1), (pert, 1)]

    def bench(d):
        assert d["radar_frames_per_s"] > 0 and d["radar_fast_frames_per_s"] > 0

    def demo(d):
        assert 1 <= d["steps"] <= 5 and len(d["true_xy"]) == len(d["est_xy"]) == d["steps"] + 1
        assert json.loads((out / "demo" / "summary.json").read_text()) == d
        assert (out / "demo" / "trajectory.png").is_file()

    return [
        (["validate", p], validate),
        (["radar", p, "--pose", *pose, "--velocity", "0.3"], radar),
        (["radar-rate", p, "--poses", "3", "--fidelity", fid[0]], rate),
        (["track", p, "--fidelity", fid[1]], track),
        (["reproduce-paper", p, "--runs", "1", "--fidelity", fid[2], "--particles", "100"],
         reproduce),
        (["layout", p, "--candidates", "2"], layout),
        (["ambiguity", p, "--grid", "0.2"], ambiguity),
        (["evaluate", p, "--episodes", "1", "--fidelity", "signal", "--task", "path"],
         evaluate("path", "signal", 1)),
        (["evaluate", p, "--episodes", "2", "--fidelity", "detections", "--task", "goal",
          "--num-envs", "2"], evaluate("goal", "detections", 2)),
        (["robustness", p, "--episodes", "1", "--severities", "0.5", "--perturbations", pert,
          "--fidelity", "detections"], robustness),
        (["bench", p, "-c", "radar", "--seconds", "0.1"], bench),
        (["demo", p, "--steps", "5", "--fidelity", "detections", "--out", str(out / "demo")],
         demo),
    ]  # fmt: skip


def extra_cases(
    path: Path, cfg: ScenarioConfig, rng: np.random.Generator, seed: int
) -> list[tuple[list[str], Check]]:
    """The slow sweep's additions: figures, the other layout searches, agents and benches."""
    p, n, out = str(path), len(cfg.reflectors.layout), path.parent
    pose = [str(v) for v in cfg.robot.start_pose]
    pert = str(rng.choice(NAMES))

    def figure(*names):
        def check(d):
            assert all((out / name).stat().st_size > 0 for name in names)

        return check

    def positive(*keys):
        def check(d):
            for key in keys:
                assert d[key] is not None and d[key] > 0, key

        return check

    def layout(d):
        assert len(d["layout"]) == n and d["evaluations"] == 2

    def positive_rows(d):
        assert d["variants"] and all(r["steps_per_s"] > 0 for r in d["variants"].values())

    def grid(d):
        assert d["localizer"] == "grid" and None not in d["grid"]["mean_errors_m"]

    cases = [
        (["layout", p, "--candidates", "2", "--types", "1", "--method", "optimize"], layout),
        (["layout", p, "--candidates", "2", "--plot", f"{out}/layout.png"], figure("layout.png")),
        (["ambiguity", p, "--grid", "0.25", "--plot", f"{out}/amb.png"], figure("amb.png")),
        (["radar", p, "--pose", *pose, "--plot", f"{out}/radar.png"], figure("radar.png")),
        (["track", p, "--fidelity", "signal", "--no-prior", "--no-ego", "--plot",
          f"{out}/track.png"], figure("track.png")),
        (["reproduce-paper", p, "--runs", "1", "--fidelity", "detections", "--true-fingerprints",
          "--plot", f"{out}/rp.png"], figure("rp.png")),
        (["reproduce-paper", p, "--runs", "1", "--fidelity", "detections", "--localizer",
          "grid"], grid),
        (["evaluate", p, "--episodes", "1", "--fidelity", "detections", "--task", "path",
          "--gif", f"{out}/ev.gif", "--plot", f"{out}/ev.png"], figure("ev.gif", "ev.png")),
        (["evaluate", p, "--episodes", "1", "--fidelity", "signal", "--task", "goal"],
         positive("mean_steps")),
        (["evaluate", p, "--episodes", "1", "--agent", "oracle"], positive("mean_steps")),
        (["evaluate", p, "--episodes", "1", "--agent", "random", "--fidelity", "detections"],
         positive("mean_steps")),
        (["robustness", p, "--episodes", "1", "--severities", "1", "--perturbations", pert,
          "--fidelity", "detections", "--plot", f"{out}/rob.png"], figure("rob.png")),
        (["bench", p, "-c", "tracking", "--seconds", "0.1"], lambda d: None),
        (["bench", p, "-c", "amcl", "--seconds", "0.1"], positive("amcl_update_ms_10000")),
    ]  # fmt: skip
    if seed % 5 == 0:  # a 1 s random-action benchmark per env variant: every fifth draw
        cases.append((["bench", p, "-c", "env", "--seconds", "0.1"], positive_rows))
    if n >= 4:  # 2 + 2 types need four reflectors (an option error otherwise)
        cases.append(
            (["layout", p, "--candidates", "2", "--types", "2", "--method", "optimize"], layout)
        )
    return cases


def run_case(capsys, argv: list[str], check: Check) -> None:
    """Run one command with ``--json``; exit 0 and a passing check, or the documented refusal."""
    with pytest.raises(SystemExit) as exc:
        main([*argv, "--json"])
    out, err = capsys.readouterr()
    if exc.value.code == 2 and argv[0] == "layout":
        assert out == "" and len(err.strip().splitlines()) == 1, err
        assert INFEASIBLE_LAYOUT.fullmatch(err.strip()), err
        return
    assert exc.value.code == 0, f"{argv}: exit {exc.value.code}\n{err}"
    data = json.loads(out, parse_constant=_no_constant)
    # parse_constant catches NaN and Infinity; a literal such as 1e999 still parses to inf
    assert all(not isinstance(v, float) or np.isfinite(v) for v in _leaves(data)), out
    check(data)


def run_draw(seed: int, folder: Path, capsys, *, extra: bool) -> None:
    path, cfg, rng = write_draw(seed, folder)
    cases = core_cases(path, cfg, rng) + (extra_cases(path, cfg, rng, seed) if extra else [])
    for argv, check in cases:
        run_case(capsys, argv, check)


@settings(
    max_examples=2,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(seed=st.integers(0, 2**32 - 1))
def test_a_random_scenario_runs_through_every_command(seed, tmp_path, capsys):
    run_draw(seed, tmp_path / str(seed), capsys, extra=False)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(40))
def test_random_scenarios_cli_sweep(seed, tmp_path, capsys):
    run_draw(seed, tmp_path, capsys, extra=True)


def test_the_accepted_layout_refusal_is_the_search_s_message():
    # The pattern follows the message: a search that cannot start is refused, as the fuzz
    # expects (eight same-type reflectors 1 m apart do not fit a 3 m room).
    from lrp_gym.errors import InputError
    from lrp_gym.placement import PlacementProblem

    data = random_scenario(np.random.default_rng(0), small=True).to_dict()
    data["room"].update(size=[3.0, 3.0, 3.0], obstacles=[])
    first = next(iter(data["reflectors"]["types"]))
    data["reflectors"]["layout"] = [
        {"position": [0.3 + 0.3 * k, 0.3 + 0.3 * k, 2.0], "type": first} for k in range(8)
    ]
    data["robot"]["start_pose"] = [1.0, 1.5, 0.0]
    data["task"]["path"] = [[1.0, 1.5], [1.4, 1.5]]
    problem = PlacementProblem.from_config(ScenarioConfig.from_dict(data))
    with pytest.raises(InputError) as exc:
        problem.sample(np.random.default_rng(0), 2, max_draws=2048)
    assert INFEASIBLE_LAYOUT.fullmatch(f"error: {exc.value}")
