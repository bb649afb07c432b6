"""``lrp-gym track`` on the paper scenario (real radar chain)."""

from __future__ import annotations

import json

import numpy as np
from typer.testing import CliRunner

from lrp_gym.cli import app


def test_track_json_summary():
    result = CliRunner().invoke(app, ["track", "ipin2023", "--seed", "1", "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert set(data) == {"frames", "raw_rmse_m", "tracked_rmse_m", "swaps", "missed_frames"}
    assert data["frames"] == 15  # 15 waypoints 0.5 m apart at 2 m/s, one frame per 0.25 s
    assert 0 <= data["missed_frames"] <= data["frames"]
    assert 0 <= data["swaps"] <= data["frames"]


def test_track_rejects_a_missing_scenario(tmp_path):
    import pytest

    from lrp_gym.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["track", str(tmp_path / "nope.yaml")])
    assert exc.value.code == 2


def test_map_aided_identification_on_the_real_chain():
    """On the paper scenario, the AMCL prior makes the tracked fingerprint several times
    closer to the truth than the paper's RCS-and-motion identification alone."""
    from lrp_gym.config import load_scenario
    from lrp_gym.experiments.track_path import run_path

    cfg = load_scenario("ipin2023")
    aided = [run_path(cfg, s).summary["tracked_rmse_m"] for s in range(2)]
    plain = [run_path(cfg, s, use_ego=False, use_prior=False).summary for s in range(2)]
    assert max(aided) < 0.3
    assert max(aided) < 0.5 * min(p["tracked_rmse_m"] for p in plain)
    # Once AMCL has converged, every frame's tracked distances sit near the truth.
    run = run_path(cfg, 0)
    late = np.abs(run.tracked_m[8:] - run.truth_m[8:])
    assert np.nanmedian(late) < 0.03


def test_track_plot_is_written_whole(tmp_path):
    out = tmp_path / "figs" / "track.png"
    result = CliRunner().invoke(app, ["track", "ipin2023", "--plot", str(out)])
    assert result.exit_code == 0, result.output
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(out.parent.glob("*.tmp*"))  # written atomically
