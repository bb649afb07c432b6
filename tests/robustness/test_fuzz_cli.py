"""Bad input everywhere: the scenario loader and every ``lrp-gym`` subcommand.

The subcommands are enumerated from the typer app at test time, so commands added later are
fuzzed too. Each CLI example carries at least one invalid value (a corrupt scenario file, a
non-number, a non-positive count, NaN, an unknown choice or option); the command must exit
with code 2 and a message, never a traceback, and must reject the input before doing real
work (each call runs under a wall-clock alarm).
"""

from __future__ import annotations

import os
import signal
import types
import typing
from pathlib import Path

import pytest
import typer
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lrp_gym.cli import app, main
from lrp_gym.config import SCENARIOS_DIR, ScenarioConfig, ScenarioError, load_scenario

GROUP = typer.main.get_command(app)
COMMANDS = sorted(GROUP.commands)
SCENARIO_PARAMS = {"scenario", "config"}
OUTPUT_PARAMS = {"out", "plot", "gif", "json_path", "plot_path", "export"}
FREE_INTS = {"seed"}  # any integer may be valid
SIGNED = {"seed", "velocity", "pose"}  # negative values are valid
ALARM_S = 60
PAPER = yaml.safe_load((SCENARIOS_DIR / "ipin2023.yaml").read_text())

FUZZ = settings(
    max_examples=12,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


def test_commands_are_enumerated():
    assert {"validate", "robustness", "evaluate", "train"} <= set(COMMANDS)


# --------------------------------------------------------------------------- scenario files
leaf = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**6), 10**6),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=8),
    st.lists(st.floats(-10, 10), max_size=4),
)


def _paths(d, prefix=()):
    if isinstance(d, dict):
        for k, v in d.items():
            yield prefix + (k,)
            yield from _paths(v, prefix + (k,))
    elif isinstance(d, list):
        for i, v in enumerate(d):
            yield prefix + (i,)
            yield from _paths(v, prefix + (i,))


PAPER_PATHS = list(_paths(PAPER))


@st.composite
def mutated_scenario(draw):
    """The paper scenario with a few leaves or sections replaced by random values."""
    import copy

    doc = copy.deepcopy(PAPER)
    for _ in range(draw(st.integers(1, 3))):
        path = draw(st.sampled_from(PAPER_PATHS))
        node = doc
        try:
            for k in path[:-1]:
                node = node[k]
            node[path[-1]] = draw(leaf)
        except (KeyError, IndexError, TypeError):
            pass
    if draw(st.booleans()):
        doc["perturbations"] = draw(
            st.dictionaries(
                st.sampled_from(["clutter", "kidnapping", "shadowing", "bogus", "interference"]),
                st.one_of(
                    leaf,
                    st.dictionaries(st.sampled_from(["severity", "frames", "count", "x"]), leaf),
                ),
                max_size=3,
            )
        )
    return doc


yaml_text = st.one_of(
    st.text(max_size=200),
    st.binary(max_size=100).map(lambda b: b.decode("latin-1")),
    mutated_scenario().map(lambda d: yaml.safe_dump(d, allow_unicode=True)),
    st.sampled_from(
        [
            "",
            "- 1\n- 2",
            "a: [",
            "room: {size: [5, 5]}",
            ": :",
            "\t\x00",
            "name: !!python/object:os.system x",
        ]
    ),
)


@FUZZ
@given(text=yaml_text)
def test_loader_fuzz_text(tmp_path_factory, text):
    f = tmp_path_factory.mktemp("y") / "s.yaml"
    f.write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        cfg = load_scenario(f)
    except ScenarioError as exc:
        assert exc.problems and all(isinstance(p, str) and p for p in exc.problems)
    else:
        assert isinstance(cfg, ScenarioConfig)


@settings(max_examples=60, deadline=None)
@given(doc=mutated_scenario())
def test_loader_fuzz_values(doc):
    try:
        cfg = ScenarioConfig.from_dict(doc)
    except ScenarioError as exc:
        assert exc.problems
        assert all(
            ":" in p or p.startswith(("radar", "at least", "expected")) for p in exc.problems
        )
    else:
        assert ScenarioConfig.from_dict(cfg.to_dict()) == cfg  # valid ones round-trip


# --------------------------------------------------------------------------- the CLI
def _base_type(hint):
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union:
        hint = next(a for a in typing.get_args(hint) if a is not type(None))
    return typing.get_origin(hint) or hint


def _spec(name):
    cmd = GROUP.commands[name]
    hints = typing.get_type_hints(cmd.callback)
    out = []
    for p in cmd.params:
        kind = _base_type(hints.get(p.name, str))
        positional = not p.opts[0].startswith("-")
        out.append((p, kind, positional))
    return out


def _corrupt_file(draw, tmp: Path) -> str:
    choice = draw(st.sampled_from(["text", "mutated", "missing", "dir", "list", "binary"]))
    f = tmp / f"bad_{draw(st.integers(0, 10**9))}.yaml"
    if choice == "missing":
        return str(tmp / "no_such_file.yaml")
    if choice == "dir":
        return str(tmp)
    if choice == "list":
        f.write_text("- 1\n- [2, 3]\n")
    elif choice == "binary":
        f.write_bytes(draw(st.binary(min_size=1, max_size=64)) + b"\xff\xfe: [")
    elif choice == "mutated":
        doc = draw(mutated_scenario())
        doc["room"] = {"size": [draw(st.sampled_from([-1.0, 0.0, float("nan")])), 5.0, 4.0]}
        f.write_text(yaml.safe_dump(doc))
    else:
        f.write_text(draw(st.text(max_size=80)) + "\n: {[")
    return str(f)


def _benign(p, kind, tmp: Path):
    """A small valid-looking value for an option that is not the poisoned one, or None to omit."""
    name = p.name
    if getattr(p, "is_flag", False):
        return None
    if name in SCENARIO_PARAMS:
        return "ipin2023" if kind is str else None
    if name in OUTPUT_PARAMS:
        return str(tmp / ("out.json" if "json" in name else "out.png"))
    if name == "model":
        return str(tmp / "missing_model.zip")
    if kind is tuple:
        return ["1.0", "1.0", "0.0"]
    if kind is int:
        return "0" if name in FREE_INTS else "1"
    if kind is float:
        return "0.5"
    return None  # free-text choices: keep the default


@st.composite
def bad_argv(draw, name: str, tmp: Path):
    spec = _spec(name)
    poisons = [("unknown", None)]
    for p, kind, positional in spec:
        if p.name in SCENARIO_PARAMS or positional:
            poisons.append(("file", p))
        elif kind in (int, float, tuple):
            poisons.append(("nan", p))
            if p.name not in SIGNED:
                poisons.append(("count", p))
        elif kind is str and p.name not in OUTPUT_PARAMS:
            poisons.append(("choice", p))
    mode, target = draw(st.sampled_from(poisons))
    argv = [name]
    opts: list[str] = []
    for p, kind, positional in spec:
        if p is target:
            if mode == "file":
                v = _corrupt_file(draw, tmp)
            elif mode == "nan":
                bad = draw(st.sampled_from(["nan", "inf", "abc", "1e999x", ""]))
                v = [bad, "0", "0"] if kind is tuple else bad
            elif mode == "count":
                # 0 is the documented "off" of an option whose default it is (--random-rooms)
                off = type(p.default) is int and p.default == 0
                ints = ["-1", "-1000000"] if off else ["-1", "0", "-1000000"]
                bad = draw(st.sampled_from(ints if kind is int else ["-1", "nan", "-inf"]))
                v = [bad, "0", "0"] if kind is tuple else bad
            else:
                v = "~" + draw(st.text(alphabet="abcxyz_-.9", max_size=6))
        elif p.required or positional or draw(st.booleans()):
            v = _benign(p, kind, tmp)
            if v is None and (p.required or positional):
                v = "ipin2023"
            if getattr(p, "is_flag", False) and draw(st.booleans()):
                opts.append(p.opts[0])
                continue
        else:
            continue
        if v is None:
            continue
        vals = v if isinstance(v, list) else [v]
        if positional:
            argv += vals
        else:
            opts += [p.opts[0], *vals]
    if mode == "unknown":
        opts.append("--definitely-not-an-option")
    return argv + opts


class _Alarm(Exception):
    pass


def run_cli(argv: list[str]) -> int:
    """Run the CLI in-process; return the exit code (an uncaught exception fails the test)."""

    def on_alarm(signum, frame):
        raise _Alarm(f"lrp-gym {' '.join(argv)} ran > {ALARM_S} s: it did work before validating")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.alarm(ALARM_S)
    try:
        main(argv)
    except SystemExit as exc:
        code = exc.code
        return 0 if code is None else (code if isinstance(code, int) else 1)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    return 0


@pytest.mark.parametrize("name", COMMANDS)
def test_cli_fuzz_bad_input_exits_2_with_message(name, tmp_path, capsys):
    cwd = os.getcwd()
    os.chdir(tmp_path)  # anything a command writes lands here
    try:

        @FUZZ
        @given(argv=bad_argv(name, tmp_path))
        def check(argv):
            capsys.readouterr()
            code = run_cli(argv)
            out, err = capsys.readouterr()
            assert code == 2, f"lrp-gym {argv}: exit {code}\n{out[-800:]}\n{err[-800:]}"
            assert "Traceback" not in err + out
            assert err.strip(), f"lrp-gym {argv}: exit 2 without a message"

        check()
    finally:
        os.chdir(cwd)


@pytest.mark.parametrize("name", COMMANDS)
def test_every_command_has_help(name, capsys):
    assert run_cli([name, "--help"]) == 0
    assert "Usage" in capsys.readouterr().out


def test_robustness_with_corrupt_model_is_a_clear_error(tmp_path, capsys):
    bad = tmp_path / "bad.zip"
    bad.write_bytes(b"not a zip")
    code = run_cli(
        [
            "robustness",
            "--agent",
            "ppo",
            "--model",
            str(bad),
            "--episodes",
            "1",
            "--perturbations",
            "clutter",
            "--severities",
            "0.5",
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and "bad.zip" in err and "Traceback" not in err


def test_random_rooms_still_reject_a_bad_scenario(tmp_path, capsys):
    """--random-rooms replaces the scenario's room, but a broken scenario is still an error
    (the fuzz found `reproduce-paper BAD.yaml --random-rooms 1` exiting 0)."""
    bad = tmp_path / "bad.yaml"
    bad.write_text("radar: {noise: [1, 2}\n")
    code = run_cli(["reproduce-paper", str(bad), "--random-rooms", "1", "--runs", "1"])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and err.strip()
