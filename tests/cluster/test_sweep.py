"""``lrp-gym sweep`` at smoke size (2 seeds x 2 learning rates, 256 steps): every trial
reports, a trial whose worker is killed resumes from its checkpoint, the best is exported, and
``--resume`` on the finished sweep gives the same trials (about a minute: integration)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("ray")
pytestmark = [pytest.mark.ray, pytest.mark.integration]
ROOT = Path(__file__).resolve().parents[2]


def sweep(tmp_path, *extra, env=None):
    argv = [sys.executable, "-m", "lrp_gym.cli", "sweep", str(ROOT / "configs/sweep-smoke.yaml")]
    argv += ["--out", str(tmp_path / "sw"), "--json", *extra]
    env = {**os.environ, "PYTHONPATH": str(ROOT), **(env or {})}
    done = subprocess.run(argv, capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout)


def test_sweep_resumes_a_lost_trial_and_exports_the_best(tmp_path):
    marker = tmp_path / "failed-once"
    doc = sweep(
        tmp_path,
        "--export",
        str(tmp_path / "best"),
        "--export-episodes",
        "2",
        env={"LRP_GYM_SWEEP_FAIL_ONCE": str(marker)},
    )
    assert marker.is_file()  # one trial (seed 0) killed its worker after its first report
    rows = doc["trials"]
    assert sorted((r["params"]["seed"], r["params"]["learning_rate"]) for r in rows) == [
        (0, 3e-4),
        (0, 1e-3),
        (1, 3e-4),
        (1, 1e-3),
    ]
    assert all(r["error"] is None and r["timesteps"] == 256 for r in rows)
    lost = [r for r in rows if r["restored_at"]]
    assert len(lost) == 1 and lost[0]["params"]["seed"] == 0
    assert lost[0]["restored_at"] == 128  # resumed from its checkpoint, trained on to 256
    key = max((r["success_rate"], r["mean_reward"]) for r in rows)
    assert (doc["best"]["success_rate"], doc["best"]["mean_reward"]) == key
    assert (tmp_path / "best" / "ppo_lrp_nav.zip").is_file()
    assert doc["export"]["final_eval"]["episodes"] == 2
    again = sweep(tmp_path, "--resume")
    assert sorted(json.dumps(r, sort_keys=True) for r in again["trials"]) == sorted(
        json.dumps(r, sort_keys=True) for r in rows
    )
