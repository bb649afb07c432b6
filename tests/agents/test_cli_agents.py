"""CLI: demo outputs, evaluate --json, and bad input exiting with code 2."""

from __future__ import annotations

import json

import numpy as np
import pytest

from lrp_gym.cli import main


def run_cli(capsys, *args: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exc:
        main(list(args))
    out, err = capsys.readouterr()
    return int(exc.value.code or 0), out, err


@pytest.mark.parametrize(
    "args, flag",
    [
        (["evaluate", "--episodes", "0"], "--episodes"),
        (["evaluate", "--agent", "sarsa", "--episodes", "1"], "--agent"),
        (
            ["evaluate", "--agent", "ppo", "--model", "/nonexistent/m.zip", "--episodes", "1"],
            "--model",
        ),
        (["evaluate", "--env", "NoSuchEnv-v0", "--episodes", "1"], "--env"),
        (["evaluate", "--task", "maze", "--episodes", "1"], "--task"),
        (["train", "--config", "/nonexistent/ppo.yaml"], "--config"),
        (["demo", "--steps", "0"], "--steps"),
        (["evaluate", "--agent-option", "no_such_gain=1", "--episodes", "1"], "--agent-option"),
        (["evaluate", "--agent-option", "creep_speed_mps", "--episodes", "1"], "--agent-option"),
        (["evaluate", "--agent-option", "creep_speed_mps=-1", "--episodes", "1"], "--agent-option"),
        (
            ["evaluate", "--agent", "random", "--agent-option", "turn_gain=2", "--episodes", "1"],
            "--agent-option",
        ),
        (
            ["robustness", "--agent-option", "avoid_walls_when_unsure=perhaps", "--episodes", "1"],
            "--agent-option",
        ),
    ],
)
def test_bad_input_exits_2_with_message(capsys, args, flag):
    code, out, err = run_cli(capsys, *args)
    assert code == 2
    assert flag in " ".join(err.split()) and "Traceback" not in err


def test_corrupt_model_exits_2(capsys, tmp_path):
    bad = tmp_path / "model.zip"
    bad.write_bytes(b"PK\x03\x04 truncated")
    code, _, err = run_cli(
        capsys,
        "evaluate",
        "--agent",
        "ppo",
        "--model",
        str(bad),
        "--env",
        "LRPRadarNavFast-v0",
        "--episodes",
        "1",
    )
    assert code == 2 and "not a readable PPO model" in " ".join(err.split())


def test_evaluate_json_has_the_documented_keys(capsys):
    code, out, _ = run_cli(
        capsys,
        "evaluate",
        "--agent",
        "random",
        "--env",
        "LRPRadarNavFast-v0",
        "--episodes",
        "2",
        "--seed",
        "7",
        "--json",
    )
    assert code == 0
    doc = json.loads(out)  # stdout is exactly one JSON document
    for key in (
        "episodes",
        "success_rate",
        "collision_rate",
        "mean_loc_error_m",
        "p95_loc_error_m",
        "time_localised",
    ):
        assert key in doc
    assert doc["episodes"] == 2 and [r["seed"] for r in doc["per_episode"]] == [7, 8]
    assert 0.0 <= doc["time_localised"] <= 1.0
    assert doc["p95_loc_error_m"] <= doc["max_loc_error_m"]


def test_evaluate_task_overrides_the_scenario_mode(capsys, monkeypatch):
    """--task goal turns a path scenario into sampled-goal episodes in its room and layout."""
    from lrp_gym.experiments import episodes as ev

    made = []
    original = ev.make_eval_env

    def spy(*args, **kwargs):
        made.append(original(*args, **kwargs))
        return made[-1]

    monkeypatch.setattr(ev, "make_eval_env", spy)
    for task in ("path", "goal"):
        args = ["evaluate", "ipin2023-2types", "--agent", "random", "--fidelity", "detections"]
        args += ["--task", task, "--episodes", "1", "--json"]
        code, out, _ = run_cli(capsys, *args)
        assert code == 0 and json.loads(out)["task"] == task
    path_env, goal_env = (e.unwrapped for e in made)
    assert path_env.cfg.task.mode == "path" and goal_env.cfg.task.mode == "goal"
    assert goal_env.cfg.reflectors == path_env.cfg.reflectors  # same layout (2 types)
    assert len(goal_env.world.layout.types) == 2


def test_demo_writes_plot_and_consistent_summary(capsys, tmp_path):
    code, out, _ = run_cli(capsys, "demo", "--steps", "12", "--out", str(tmp_path), "--seed", "1")
    assert code == 0
    assert (tmp_path / "trajectory.png").stat().st_size > 10_000
    s = json.loads((tmp_path / "summary.json").read_text())
    true_xy, est_xy = np.array(s["true_xy"]), np.array(s["est_xy"])
    assert s["steps"] <= 12 and len(true_xy) == s["steps"] + 1
    err = np.linalg.norm(true_xy[1:] - est_xy[1:], axis=1)
    assert s["mean_loc_error_m"] == pytest.approx(err.mean(), abs=1e-9)
    assert s["waypoints_m"][0] == [0.75, 0.75] and len(s["waypoints_m"]) == 15
    assert "true x" in out


def test_agent_options_reach_the_policy_and_the_record(capsys):
    """``--agent-option`` sets pure pursuit's config (typed), and the JSON records it; a
    creep speed of 0 (a robot that starts unlocalised stands instead of creeping) changes
    the episode."""
    from agents.pure_pursuit import parse_options

    assert parse_options(["avoid_walls_when_unsure=ON", "creep_speed_mps=0.2"]) == {
        "avoid_walls_when_unsure": True,
        "creep_speed_mps": 0.2,
    }
    common = ("evaluate", "--env", "LRPRadarNavFast-v0", "--task", "goal", "--episodes", "1")
    code, out, _ = run_cli(capsys, *common, "--agent-option", "creep_speed_mps=0", "--json")
    assert code == 0
    doc = json.loads(out)
    assert doc["agent_options"] == {"creep_speed_mps": 0.0}
    code, out, _ = run_cli(capsys, *common, "--json")
    assert json.loads(out)["agent_options"] == {}
    assert json.loads(out)["per_episode"][0] != doc["per_episode"][0]
    # robustness records them the same way, {} when none is given
    cell = ("--perturbations", "clutter", "--severities", "0.5", "--json")
    code, out, _ = run_cli(capsys, "robustness", *common[1:], *cell)
    assert code == 0 and json.loads(out)["agent_options"] == {}
