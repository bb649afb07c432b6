"""Episodes run several robots at a time give exactly the sequential runs' results."""

from __future__ import annotations

import json

import numpy as np
import pytest

from agents.pure_pursuit import PurePursuitPolicy
from lrp_gym.cli import main
from lrp_gym.experiments.episodes import episode_results, make_eval_env
from lrp_gym.experiments.robustness import run_cell


def _rows(results):
    return [r.row() for r in results]


def test_batched_episodes_equal_sequential_ones():
    env = make_eval_env("pure-pursuit", "LRPRadarNavFast-v0", overrides={"task": {"mode": "goal"}})
    policy = PurePursuitPolicy.from_env(env)
    seeds = [40, 41, 42, 43, 44]
    one = episode_results(env, policy, seeds)
    three = episode_results(env, policy, seeds, num_envs=3)
    assert [r.seed for r in three] == seeds
    assert _rows(three) == _rows(one)
    for a, b in zip(one, three, strict=True):
        np.testing.assert_array_equal(a.loc_error_m, b.loc_error_m)
        np.testing.assert_array_equal(a.true_xy, b.true_xy)


def test_batched_cell_keeps_each_episodes_kidnap_frame():
    cell = {"perturbations": {"kidnapping": {"severity": 1.0, "frames": [3, 6]}}}
    env = make_eval_env("pure-pursuit", "LRPRadarNavFast-v0", "ipin2023", overrides=cell)
    policy = PurePursuitPolicy.from_env(env)
    seq = run_cell(env, policy, "kidnapping", 1.0, 3, seed=5)
    batched = run_cell(env, policy, "kidnapping", 1.0, 3, seed=5, num_envs=3)
    assert seq == batched
    assert seq["kidnapped_episodes"] == 3  # every episode kept its own kidnap frame


def test_num_envs_flag_is_checked(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["evaluate", "--num-envs", "0", "--episodes", "1"])
    assert exc.value.code == 2
    assert "--num-envs" in capsys.readouterr().err


def test_evaluate_num_envs_gives_the_same_json(capsys):
    args = ["evaluate", "--agent", "pure-pursuit", "--fidelity", "detections", "--json"]
    args += ["--episodes", "3", "--seed", "9"]
    outputs = []
    for extra in ([], ["--num-envs", "2"]):
        with pytest.raises(SystemExit) as exc:
            main([*args, *extra])
        assert exc.value.code == 0
        outputs.append(json.loads(capsys.readouterr().out))
    assert outputs[0] == outputs[1]
