"""The README's results table equals what docs/results/*.json say (no rerun)."""

from __future__ import annotations

import json

import pytest

from lrp_gym.commands import _results as res


def test_readme_table_matches_the_stored_results():
    readme = res.README.read_text(encoding="utf-8")
    table = res.render_table(res.load_results())
    assert res.replace_table(readme, table) == readme, "run `lrp-gym report`"


def test_every_stored_result_belongs_to_a_row_and_names_its_command():
    keys = {r.key: r for r in res.ROWS}
    for f in res.RESULTS_DIR.glob("*.json"):
        assert f.stem in keys, f"{f.name}: no row in lrp_gym/commands/_results.py"
        doc = json.loads(f.read_text())
        row = keys[f.stem]
        if row.argv is None:  # several runs: exactly the row's commands, in order
            assert doc["command"] == [f"lrp-gym {' '.join(a)} --json" for a in row.runs]
            assert len(doc["result"]) == len(row.runs)
        else:
            assert doc["command"].startswith(row.shown_command)


def test_every_row_is_regenerated_or_says_why_not():
    for row in res.ROWS:
        assert row.commands or row.source is not None or "not rerun" in row.what, row.key


def test_rerun_of_a_row_with_several_runs_stores_them_all(tmp_path, monkeypatch):
    import subprocess

    from lrp_gym.commands import report

    row = next(r for r in res.ROWS if r.key == "placement_methods")
    seen = []

    def fake_run(cmd, **_kw):
        argv = cmd[3:]
        seen.append(argv)
        method = argv[argv.index("--method") + 1]
        out = {"method": method, "ambiguous_fraction": 0.1 if method == "optimize" else 0.2}
        return subprocess.CompletedProcess(cmd, 0, json.dumps(out), "")

    monkeypatch.setattr(report.subprocess, "run", fake_run)
    monkeypatch.setattr(res, "RESULTS_DIR", tmp_path)
    report._rerun(row)
    assert seen == [[*a, "--json"] for a in row.runs] and len(seen) == 10
    doc = json.loads((tmp_path / "placement_methods.json").read_text())
    assert [r["method"] for r in doc["result"]] == ["random", "optimize"] * 5
    data = res.load_results(tmp_path)
    text = res.render_row(row, data)
    assert "20.0 % vs 10.0 %" in text and "better on 5 of 5" in text and "(missed)" not in text


def test_placement_and_bench_rows_say_missed_and_busy():
    row = next(r for r in res.ROWS if r.key == "placement_methods")
    worse = [
        {"method": m, "ambiguous_fraction": f} for m, f in (("random", 0.1), ("optimize", 0.2))
    ]
    assert "(missed)" in res.render_row(row, {row.key: worse})
    bench = next(r for r in res.ROWS if r.key == "bench_radar")
    r = {"radar_frames_per_s": 1200.0, "radar_fast_frames_per_s": 2000.0}
    idle = r | {"machine": {"cpus": 2, "load_avg_1min": 0.2}}
    busy = r | {"machine": {"cpus": 2, "load_avg_1min": 5.0}}
    assert "not representative" not in res.render_row(bench, {bench.key: idle})
    assert "not representative" in res.render_row(bench, {bench.key: busy})
    assert "(missed)" in res.render_row(bench, {bench.key: busy | {"radar_frames_per_s": 900.0}})


def test_training_row_reads_the_shipped_model_card():
    row = next(r for r in res.ROWS if r.key == "ppo_training")
    card = json.loads(row.source.read_text())
    text = res.render_row(row, res.load_results())
    assert "(not regenerated)" not in text
    assert f"{card['wall_time_s'] / 60:.1f} min" in text and f"{card['timesteps']:,}" in text


def test_missed_and_not_regenerated_marks():
    row = next(r for r in res.ROWS if r.key == "layout_random")
    base = {"search_s": 4.2, "ambiguous_fraction": 0.12}
    assert "(missed)" not in res.render_row(row, {row.key: base})
    assert res.render_row(row, {row.key: base | {"search_s": 25.0}}).count("(missed)") == 1
    assert "(not regenerated)" in res.render_row(row, {})
    ppo = next(r for r in res.ROWS if r.key == "ppo_goal")
    m = {"success_rate": 0.95, "collision_rate": 0.0, "mean_loc_error_m": 0.2}
    m |= {"p95_loc_error_m": 0.5}
    pp = m | {"success_rate": 0.92}
    assert "(missed)" not in res.render_row(ppo, {"ppo_goal": m, "pp_goal": pp})
    low = m | {"success_rate": 0.85}
    assert "(missed)" in res.render_row(ppo, {"ppo_goal": low, "pp_goal": pp})


def test_report_check_and_bad_only(capsys):
    from lrp_gym.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["report", "--check"])
    assert exc.value.code == 0
    with pytest.raises(SystemExit) as exc:
        main(["report", "--rerun", "--only", "pp_pth"])
    assert exc.value.code == 2 and "did you mean 'pp_path'" in capsys.readouterr().err
