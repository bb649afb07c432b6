"""configs/ppo.yaml is an rl-baselines3-zoo file: ``python -m rl_zoo3.train`` trains from it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

pytest.importorskip("rl_zoo3", reason="the zoo extra (make install adds it)")


@pytest.mark.integration
@pytest.mark.timeout(600)
@pytest.mark.parametrize("env_id", ["LRPRadarNavFast-v0", "LRPRadarNav-v0"])
def test_rl_zoo3_trains_from_the_config_unchanged(tmp_path, env_id):
    # Only the rollout is shortened (smoke size); every key of the section goes through the zoo.
    argv = [sys.executable, "-m", "rl_zoo3.train", "--algo", "ppo", "--env", env_id]
    argv += ["--gym-packages", "lrp_gym", "-conf", str(REPO / "configs" / "ppo.yaml")]
    argv += ["-n", "64", "-f", str(tmp_path / "logs"), "--seed", "0", "--eval-freq", "-1"]
    argv += ["--hyperparams", "n_steps:32", "batch_size:32", "n_epochs:1"]
    res = subprocess.run(argv, cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-3000:]
    run = tmp_path / "logs" / "ppo" / f"{env_id}_1"
    assert (run / f"{env_id}.zip").is_file(), res.stdout[-2000:]
    assert (run / env_id / "vecnormalize.pkl").is_file()  # the zoo applied `normalize`
