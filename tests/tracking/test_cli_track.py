"""``lrp-gym track`` on the paper scenario (real radar chain)."""

from __future__ import annotations

import json

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
