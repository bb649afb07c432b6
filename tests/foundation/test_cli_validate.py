"""The CLI's validate command: output, errors, exit codes."""

from __future__ import annotations

import json
import subprocess
import sys

import yaml

from lrp_gym.config import SCENARIOS_DIR


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "lrp_gym.cli", *args], capture_output=True, text=True, timeout=120
    )


def test_validate_prints_derived_numbers():
    res = run("validate", str(SCENARIOS_DIR / "ipin2023.yaml"))
    assert res.returncode == 0, res.stderr
    assert "range resolution" in res.stdout and "0.0749 m" in res.stdout
    assert "19.112 m" in res.stdout


def test_validate_json():
    res = run("validate", "ipin2023", "--json")
    assert res.returncode == 0
    data = json.loads(res.stdout)
    assert data["valid"] is True
    assert abs(data["radar"]["range_resolution_m"] - 0.075) < 1e-3
    assert len(data["reflectors"]) == 4


def test_broken_scenario_exits_2_with_clear_errors(tmp_path):
    data = yaml.safe_load((SCENARIOS_DIR / "ipin2023.yaml").read_text())
    data["room"]["size"] = [5, -1, 4]
    data["radar"]["windw"] = "hann"
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(data))
    res = run("validate", str(bad))
    assert res.returncode == 2
    assert "room.size: expected 3 positive numbers, got [5, -1, 4]" in res.stderr
    assert "radar.windw: unknown key" in res.stderr
    assert "Traceback" not in res.stderr + res.stdout


def test_missing_file_and_bad_option_exit_2(tmp_path):
    res = run("validate", str(tmp_path / "nope.yaml"))
    assert res.returncode == 2 and "file not found" in res.stderr
    res = run("validate", "--bogus")
    assert res.returncode == 2
    assert "Traceback" not in res.stderr
