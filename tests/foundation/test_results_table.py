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
        assert doc["command"].startswith(keys[f.stem].shown_command)


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
