import json

import numpy as np
import pytest

from lrp_gym.cli import main
from lrp_gym.experiments.reproduce import converged_after


def test_converged_after_definition():
    assert converged_after(np.array([1.0, 0.5, 0.1, 0.2, 0.05, 0.01])) == 5
    assert converged_after(np.array([0.1, 0.1])) == 1
    assert converged_after(np.array([0.1, 0.3])) is None


def test_reproduce_paper_smoke(tmp_path, capsys):
    out = tmp_path / "r.json"
    with pytest.raises(SystemExit) as exc:
        main(
            [
                "reproduce-paper",
                "--runs",
                "1",
                "--no-noise",
                "--particles",
                "1000",
                "--out",
                str(out),
                "--plot",
                str(tmp_path / "e.png"),
            ]
        )
    assert exc.value.code == 0
    data = json.loads(out.read_text())
    assert data["positions"] == 15 and data["runs"] == 1
    assert len(data["lut"]["errors_m"]) == len(data["amcl"]["mean_errors_m"]) == 15
    assert data["lut"]["entries"] > 1000
    assert all(e >= 0 for e in data["amcl"]["mean_errors_m"])
    assert data["amcl"]["std_errors_m"] == [0.0] * 15  # one run
    assert data["amcl"]["mean_error_m"] == pytest.approx(np.mean(data["amcl"]["mean_errors_m"]))
    assert data["amcl"]["converged_after"] == converged_after(
        np.array(data["amcl"]["mean_errors_m"])
    )
    assert (tmp_path / "e.png").stat().st_size > 1000
    assert "AMCL mean error" in capsys.readouterr().out


def test_reproduce_paper_rejects_bad_noise():
    with pytest.raises(SystemExit) as exc:
        main(["reproduce-paper", "--noise", "maybe"])
    assert exc.value.code == 2


def test_grid_runs_on_the_same_detections_without_changing_amcl(paper_cfg):
    from lrp_gym.experiments.reproduce import reproduce

    cfg = paper_cfg.with_overrides(
        {
            "radar": {"noise": False},
            "localization": {
                "initial_particles": 1000,
                "max_particles": 1000,
                "grid_cell_m": 0.1,
                "grid_cell_deg": 10.0,
            },
        }
    )
    alone = reproduce(cfg, runs=1, seed=3, estimator="cluster")
    both = reproduce(cfg, runs=1, seed=3, estimator="cluster", localizer="grid")
    # The grid draws nothing: same generator stream, so the same detections, LUT and AMCL.
    np.testing.assert_array_equal(both.amcl_errors_m, alone.amcl_errors_m)
    np.testing.assert_array_equal(both.lut_errors_m, alone.lut_errors_m)
    assert alone.grid_errors_m is None and "grid" not in alone.to_dict()
    grid = both.to_dict()["grid"]
    assert grid["mean_error_m"] < 0.15, grid
    assert len(grid["mean_errors_m"]) == 15


def test_reproduce_paper_rejects_an_unknown_localizer():
    with pytest.raises(SystemExit) as exc:
        main(["reproduce-paper", "--localizer", "kalman"])
    assert exc.value.code == 2


def test_runs_that_share_the_prototype_filter_equal_runs_built_afresh(paper_cfg):
    """The bench builds AMCL (its visibility table, grids, link) once; each run's filter is
    a spawn of it. Run 2 of the loop equals run 2 with its own bench and filter (a runner that
    rebuilds the bench for every unit), in a room where the model has a visibility table."""
    from lrp_gym.experiments import reproduce as rp

    cfg = paper_cfg.with_overrides(
        {
            "room": {"obstacles": [{"min": [0.8, 1.4, 0.0], "max": [2.2, 2.6, 1.0]}]},
            "localization": {"initial_particles": 1000, "max_particles": 1000},
        }
    )

    def afresh(task, items):
        out = []
        for _, unit in items:
            rp._BENCHES.clear()  # a new bench: a new prototype filter
            out.append(task(unit))
        return out

    shared = rp.reproduce(cfg, runs=2, seed=5)
    fresh = rp.reproduce(cfg, runs=2, seed=5, runner=afresh)
    assert shared.amcl_errors_m.shape == (2, 15)
    np.testing.assert_array_equal(shared.amcl_errors_m, fresh.amcl_errors_m)
    np.testing.assert_array_equal(shared.amcl_particles, fresh.amcl_particles)
