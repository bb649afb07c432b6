"""The CLI grammar (README, "CLI grammar"), checked on every command of the typer app.

Commands are enumerated from the app, so commands added later are held to the same rules.
"""

from __future__ import annotations

import json
import os
import re
import typing

import pytest
import typer

from lrp_gym.cli import app, main
from lrp_gym.commands._common import DEFAULT_SCENARIO, check_output
from lrp_gym.config import SCENARIOS_DIR
from lrp_gym.errors import InputError

GROUP = typer.main.get_command(app)
COMMANDS = sorted(GROUP.commands)


def _params(name):
    return {p.name: p for p in GROUP.commands[name].params}


def _opt(name, flag):
    return next((p for p in GROUP.commands[name].params if flag in p.opts), None)


def run(capsys, *argv):
    with pytest.raises(SystemExit) as exc:
        main(list(argv))
    out, err = capsys.readouterr()
    return exc.value.code, out, err


@pytest.mark.parametrize("name", COMMANDS)
def test_scenario_is_optional_positional_with_set(name):
    p = _params(name).get("scenario")
    if p is None:
        assert _opt(name, "--set") is None, "--set needs a SCENARIO"
        return
    assert not p.opts[0].startswith("-"), "SCENARIO is positional"
    assert not p.required and p.default == DEFAULT_SCENARIO
    assert _opt(name, "--set") is not None and _opt(name, "--set").multiple


@pytest.mark.parametrize("name", COMMANDS)
def test_json_prints_and_out_writes(name):
    js, out = _opt(name, "--json"), _opt(name, "--out")
    if js is not None:
        assert js.is_flag, "--json is a switch: JSON to stdout"
    if out is not None:
        assert not out.is_flag
        assert re.search(r"\b(file|folder)\b", out.help), "--out says file or folder"


SCENARIO_JSON_COMMANDS = [
    n for n in COMMANDS if "scenario" in _params(n) and _opt(n, "--json") is not None
]
FILE_OUT_COMMANDS = [
    n for n in COMMANDS if _opt(n, "--out") is not None and _opt(n, "--out").metavar != "FOLDER"
]


@pytest.mark.parametrize("name", SCENARIO_JSON_COMMANDS)
def test_every_json_command_can_write_its_result_to_a_file(name):
    out = _opt(name, "--out")
    assert out is not None, "--json prints the result; --out PATH writes it"
    assert out.metavar in ("FOLDER", "FILE.json", "FILE.yaml"), "the file type is in the help"
    if out.metavar != "FOLDER":
        assert _opt(name, "--force") is not None, "an existing file needs --force"


@pytest.mark.parametrize("name", FILE_OUT_COMMANDS)
def test_out_is_checked_before_any_work(name, tmp_path, capsys, monkeypatch):
    import lrp_gym.config
    import lrp_gym.envs.nav_env  # noqa: F401  (imported first, it binds the real function)
    import lrp_gym.radar.calibrate  # noqa: F401  (same)

    def no_work(*_a, **_k):
        raise AssertionError(f"{name} loaded its scenario before checking --out")

    monkeypatch.setattr(lrp_gym.config, "load_scenario", no_work)
    suffix = _opt(name, "--out").metavar.removeprefix("FILE")
    existing, folder = tmp_path / f"mine{suffix}", tmp_path / f"dir{suffix}"
    existing.write_text("# mine\n")
    folder.mkdir()
    extra = ["--pose", "2", "2", "0"] if name == "radar" else []
    code, out, err = run(capsys, name, *extra, "--out", str(existing))
    assert code == 2 and out == ""
    assert err.startswith("error: --out:") and "--force" in err
    assert existing.read_text() == "# mine\n"
    code, _, err = run(capsys, name, *extra, "--out", str(folder))
    assert code == 2 and "--out" in err and "folder" in err


@pytest.mark.parametrize(
    "argv",
    [
        ["validate"],
        ["radar", "--pose", "2", "2", "0"],
        ["radar-rate", "--poses", "3", "--fidelity", "detections"],
        ["track", "--fidelity", "detections"],
    ],
)
def test_out_writes_what_json_prints(argv, tmp_path, capsys):
    path = tmp_path / "r.json"
    code, out, err = run(capsys, *argv, "--json", "--out", str(path))
    assert code == 0
    assert json.loads(out) == json.loads(path.read_text())
    assert err.strip().splitlines() == [f"wrote {path}"]
    path.unlink()
    code, out, _ = run(capsys, *argv, "--out", str(path))
    assert code == 0 and path.is_file()
    assert out.strip().splitlines()[-1] == f"wrote {path}"


@pytest.mark.parametrize("name", [n for n in COMMANDS if "scenario" in _params(n)])
def test_hidden_scenario_alias(name, capsys, monkeypatch):
    alias = _opt(name, "--scenario")
    assert alias is not None and alias.hidden, "old scripts pass --scenario NAME"
    monkeypatch.setenv("COLUMNS", "80")
    _, out, _ = run(capsys, name, "--help")
    assert "--scenario" not in out


def test_scenario_alias_means_the_positional(capsys):
    code, out, _ = run(capsys, "validate", "--scenario", "ipin2023-2types", "--json")
    assert code == 0 and json.loads(out)["name"] == "ipin2023-2types"
    code, out, _ = run(
        capsys, "validate", "ipin2023-2types", "--scenario=ipin2023-2types", "--json"
    )
    assert code == 0 and json.loads(out)["name"] == "ipin2023-2types"
    code, _, err = run(capsys, "validate", "ipin2023", "--scenario", "ipin2023-2types")
    assert code == 2 and err.startswith("error: --scenario:") and "twice" in err
    _, _, err = run(capsys, "validate", "--scenario", "ipin2032")
    assert "did you mean 'ipin2023'" in err


@pytest.mark.parametrize("name", COMMANDS)
def test_switches_and_choices(name):
    hints = typing.get_type_hints(GROUP.commands[name].callback)
    for p in GROUP.commands[name].params:
        if hints.get(p.name) is bool:
            assert p.is_flag, f"{p.opts}: a boolean takes no value"
            if p.default is True:
                assert p.secondary_opts, f"{p.opts}: default-on switch needs --no-x"
        assert "--fingerprints" not in p.opts
    fid = _opt(name, "--fidelity")
    if fid is not None:
        assert fid.metavar == "signal|detections"


@pytest.mark.parametrize("name", COMMANDS)
def test_help_reads_at_80_columns(name, capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "80")
    code, out, _ = run(capsys, name, "--help")
    assert code == 0
    assert "<bool>" not in out and "{" not in out and "``" not in out
    # no typer/click type labels: metavars say what a value is (SCENARIO, N, FILE.json)
    assert not re.search(r"<(str|int|float|path|text)>|\b(TEXT|INTEGER|FLOAT)\b", out)
    assert max(len(line) for line in out.splitlines()) <= 80


def test_version(capsys):
    from lrp_gym import __version__

    code, out, _ = run(capsys, "--version")
    assert code == 0 and __version__ in out


@pytest.mark.parametrize(
    "argv, flag",
    [
        (["radar", "--pose", "2", "2"], "--pose"),
        (["radar-rate", "--poses", "0"], "--poses"),
        (["bench", "--seconds", "0"], "--seconds"),
        (["validate", "--json", "false"], "SCENARIO"),
        (["radar-rate", "--fidelity", "signl"], "--fidelity"),
        (["reproduce-paper", "--noise", "maybe"], "SCENARIO"),
    ],
)
def test_one_error_line_exit_2(argv, flag, capsys):
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert err.startswith("error: ") and flag in err
    assert len(err.strip().splitlines()) == 1 and "╭" not in err


def test_did_you_mean(capsys):
    _, _, err = run(capsys, "validate", "ipin2032")
    assert "did you mean 'ipin2023'" in err
    _, _, err = run(capsys, "radar-rate", "--fidelity", "signl")
    assert "did you mean 'signal'" in err


# --------------------------------------------------------------------------- file safety
def test_check_output_rules(tmp_path):
    f = tmp_path / "a.json"
    assert check_output(f, "--out") == f
    f.write_text("{}")
    with pytest.raises(InputError, match="--force"):
        check_output(f, "--out")
    assert check_output(f, "--out", force=True) == f
    with pytest.raises(InputError, match="folder"):
        check_output(tmp_path, "--out")
    with pytest.raises(InputError, match="not a folder"):
        check_output(f / "x.json", "--out")
    with pytest.raises(InputError, match="shipped"):
        check_output(SCENARIOS_DIR / "ipin2023.yaml", "--out", force=True)
    with pytest.raises(InputError, match=r"\.png"):
        check_output(tmp_path / "m.txt", "--plot", suffixes=(".png",))


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_check_output_unwritable(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir(mode=0o500)
    with pytest.raises(InputError, match="permission"):
        check_output(ro / "a.json", "--out")


def test_layout_never_replaces_the_users_scenario(tmp_path, capsys):
    mine = tmp_path / "my.yaml"
    text = "# my comments\n" + (SCENARIOS_DIR / "ipin2023.yaml").read_text()
    mine.write_text(text)
    code, _, err = run(capsys, "layout", str(mine), "--out", str(mine), "--candidates", "1")
    assert code == 2 and "--force" in err and mine.read_text() == text
    shipped = SCENARIOS_DIR / "ipin2023.yaml"
    before = shipped.read_text()
    code, _, err = run(capsys, "layout", "--out", str(shipped), "--force", "--candidates", "1")
    assert code == 2 and "shipped" in err and shipped.read_text() == before


def test_bad_second_output_fails_before_the_first_is_written(tmp_path, capsys):
    out, plot = tmp_path / "r.json", tmp_path / "figs"
    plot.mkdir()
    code, _, err = run(
        capsys, "reproduce-paper", "--runs", "1", "--out", str(out), "--plot", str(plot)
    )
    assert code == 2 and "--plot" in err
    assert list(tmp_path.iterdir()) == [plot]  # nothing written, no .tmp left


def test_wrote_line_and_json_stdout(tmp_path, capsys):
    png = tmp_path / "m.png"
    code, out, err = run(capsys, "ambiguity", "--grid", "0.2", "--json", "--plot", str(png))
    assert code == 0 and json.loads(out)["plot"] == str(png)
    assert f"wrote {png}" in err and png.stat().st_size > 1000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.png"]


def test_radar_json_has_the_tables_columns(capsys):
    code, out, _ = run(capsys, "radar", "--pose", "2", "2", "0", "--json")
    det = json.loads(out)["detections"]
    assert code == 0 and det
    assert set(det[0]) == {"range_m", "velocity_mps", "power_dbm", "rcs_dbsm", "snr_db"}


@pytest.mark.parametrize("name", COMMANDS)
def test_every_model_path_option_says_what_loading_a_model_runs(name):
    """A model file (SB3 zip) may hold pickles, and unpickling runs code: every option that
    takes one says so, and what lrp-gym does about it."""
    for p in GROUP.commands[name].params:
        if (getattr(p, "metavar", None) or "").lower().endswith(".zip"):
            assert "pickle" in (p.help or ""), f"{name} {p.opts}: help does not mention pickles"
