"""``lrp-gym radar`` and ``lrp-gym radar-rate``: output, exit codes, the figure."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "lrp_gym.cli", *args], capture_output=True, text=True, timeout=120
    )


def test_radar_json_true_distances_and_detections_near_them(paper_world):
    res = run("radar", "ipin2023", "--pose", "2", "2", "0", "--json")
    assert res.returncode == 0, res.stderr
    data = json.loads(res.stdout)
    true = np.array(data["true_lrp_distances_m"])
    np.testing.assert_allclose(true, paper_world.true_distances_m(np.array([2.0, 2.0])))
    assert len(true) == 4
    rng = np.array([d["range_m"] for d in data["detections"]])
    assert np.all(np.min(np.abs(rng[None, :] - true[:, None]), axis=1) < 0.1)


def test_radar_bad_pose_exits_2():
    res = run("radar", "ipin2023", "--pose", "9", "2", "0")
    assert res.returncode == 2
    assert "--pose" in res.stderr + res.stdout
    assert "Traceback" not in res.stderr


def test_radar_plot_writes_png(tmp_path):
    out = tmp_path / "rd.png"
    res = run("radar", "ipin2023", "--pose", "2", "2", "0.5", "--velocity", "1", "--plot", str(out))
    assert res.returncode == 0, res.stderr
    assert out.stat().st_size > 10_000
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_radar_rate_json():
    res = run("radar-rate", "ipin2023", "--poses", "20", "--json")
    assert res.returncode == 0, res.stderr
    data = json.loads(res.stdout)
    assert data["n_poses"] == 20 and data["n_lrps"] == 4
    assert 0.0 <= data["range_only_rate"] <= 1.0 and data["rate"] <= data["range_only_rate"]
    bad = run("radar-rate", "ipin2023", "--fidelity", "exact")
    assert bad.returncode == 2
