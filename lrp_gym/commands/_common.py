"""Helpers shared by the subcommands: the CLI grammar's common options, checks and writers.

The grammar (README, "CLI grammar"; enforced by tests/foundation/test_cli_grammar.py):
an optional positional SCENARIO (default ipin2023) with ``--set`` wherever a scenario is used,
``--json`` prints JSON to stdout, ``--out PATH`` writes the main result to a file (or a run
folder), ``--fidelity signal|detections``, ``--x/--no-x`` switches, one ``error: ...`` line
with exit code 2 for bad input and one ``wrote PATH`` line per file written.
"""

from __future__ import annotations

import contextlib
import difflib
import json
import math
import os
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import typer
from rich.console import Console
from typer.core import TyperArgument, TyperCommand, TyperOption

from lrp_gym.errors import InputError
from lrp_gym.output import atomic_path, save_figure, to_jsonable, write_json, write_text

__all__ = ["atomic_path", "save_figure", "to_jsonable", "write_json", "write_text"]

console = Console()
err_console = Console(stderr=True)

DEFAULT_SCENARIO = "ipin2023"
FIDELITIES = ("signal", "detections")
SetHelp = (
    "Override a scenario setting, KEY.PATH=VALUE (the value is read as YAML), e.g. "
    "localization.measurements=tracks; repeatable."
)


# --------------------------------------------------------------------------- common options
def scenario_argument() -> Any:
    """The optional positional SCENARIO every scenario-using command takes."""
    return typer.Argument(
        DEFAULT_SCENARIO,
        metavar="SCENARIO",
        help="Scenario YAML file, or the name of one in configs/scenarios.",
        show_default=True,
    )


class ScenarioCommand(TyperCommand):
    """A command whose positional SCENARIO also answers to a hidden ``--scenario`` option.

    Older scripts wrote ``--scenario NAME``; the option is kept as an alias, hidden from the
    help, so the grammar stays "SCENARIO is positional". The help shows the argument as
    ``SCENARIO`` without typer's ``<str>`` type label. The CLI installs this class on every
    command (:func:`lrp_gym.cli._register_all`); commands without a SCENARIO are unchanged.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        for p in self.params:  # a required positional (sweep's CONFIG): its metavar, plainly
            if isinstance(p, TyperArgument) and p.required:
                p.__class__ = _RequiredArgument
        arg = next((p for p in self.params if p.name == "scenario"), None)
        if arg is None:
            return
        arg.__class__ = _ScenarioArgument
        self.params.append(
            TyperOption(
                param_decls=["--scenario", _ALIAS],
                type_descriptor=arg.type_descriptor,  # type: ignore[attr-defined]  # typer's
                default=None,
                metavar="SCENARIO",
                hidden=True,
            )
        )

    def parse_args(self, ctx: typer.Context, args: list[str]) -> list[str]:  # type: ignore[override]
        own = {o for p in self.params for o in getattr(p, "opts", ())}
        rest = super().parse_args(ctx, fill_optional_values(args, own))
        alias = ctx.params.pop(_ALIAS, None)
        if alias is not None:
            source = ctx.get_parameter_source("scenario")
            given = source is not None and source.name != "DEFAULT"
            if given and ctx.params["scenario"] != alias:
                raise InputError(
                    f"--scenario: SCENARIO given twice ({ctx.params['scenario']!r} and "
                    f"{alias!r}); give it once, as the positional argument"
                )
            ctx.params["scenario"] = alias
        return rest


_ALIAS = "scenario_alias"

#: Options whose value may be left out, and what a bare one means (``--ray`` alone: a Ray
#: started here). typer's parser has no optional values, so the value is filled in first.
OPTIONAL_VALUES = {"--ray": "local"}


def fill_optional_values(args: list[str], options: set[str]) -> list[str]:
    """``args`` with the value of every bare optional-value option among ``options`` filled
    in: one followed by nothing or by another option (``--ray --episodes 5``)."""
    out: list[str] = []
    for i, arg in enumerate(args):
        if arg == "--":
            return out + args[i:]
        out.append(arg)
        if arg in OPTIONAL_VALUES and arg in options:
            following = args[i + 1] if i + 1 < len(args) else None
            if following is None or following.startswith("-"):
                out.append(OPTIONAL_VALUES[arg])
    return out


class _ScenarioArgument(TyperArgument):
    def display_type_rich(self, ctx: typer.Context) -> str | None:  # type: ignore[override]
        return None  # the metavar SCENARIO and the help say what it is; no "<str>"


class _RequiredArgument(TyperArgument):
    def display_type_rich(self, ctx: typer.Context) -> str | None:  # type: ignore[override]
        return None  # the metavar (CONFIG) and the help say what it is; no "<path>"

    def _usage_display_name(self) -> str:
        return self.display_name_raw  # CONFIG, not typer's {CONFIG}


def sets_option() -> Any:
    """``--set KEY.PATH=VALUE`` (repeatable)."""
    return typer.Option(None, "--set", metavar="KEY.PATH=VALUE", help=SetHelp)


def fidelity_option() -> Any:
    """``--fidelity signal|detections`` (default: the scenario's radar.fidelity)."""
    return typer.Option(
        None,
        "--fidelity",
        metavar="signal|detections",
        help="Radar model: signal (FMCW beat signal, FFT, CFAR) or detections (drawn from the "
        "channel's paths; fast). Default: the scenario's radar.fidelity.",
    )


def json_option(what: str = "the results") -> Any:
    """``--json``: print JSON to stdout and nothing else."""
    return typer.Option(False, "--json", help=f"Print {what} as JSON to stdout (nothing else).")


def out_option(what: str, metavar: str = "FILE.json") -> Any:
    """``--out PATH``: write the main result to a file (say which kind in ``what``)."""
    return typer.Option(None, "--out", metavar=metavar, help=f"Write {what} to this file.")


def plot_option(what: str) -> Any:
    """``--plot FILE.png``: write a figure."""
    return typer.Option(
        None, "--plot", metavar="FILE.png", help=f"Write {what} to this image (.png, .pdf, .svg)."
    )


def force_option() -> Any:
    """``--force``: allow replacing an existing output file."""
    return typer.Option(False, "--force", help="Replace output files that already exist.")


def seed_option(what: str = "Seed of the random generator.") -> Any:
    """``--seed N``."""
    return typer.Option(0, "--seed", metavar="N", help=what)


# --------------------------------------------------------------------------- checks
def choice(value: str | None, options: Sequence[str], flag: str) -> str | None:
    """``value`` if it is one of ``options`` (None passes), else an InputError with a hint."""
    if value is None or value in options:
        return value
    close = difflib.get_close_matches(value, options, n=1, cutoff=0.5)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise InputError(f"{flag}: unknown {value!r}{hint} (choose from {', '.join(options)})")


@contextlib.contextmanager
def as_flags(**flags: str) -> Iterator[None]:
    """Turn a library ``ValueError("name: ...")`` into an InputError naming the CLI flag.

    The library names its own arguments (``candidates``, ``model_path``); only the commands
    know which flag sets each one, e.g. ``as_flags(model_path="--model")``.
    """
    try:
        yield
    except ValueError as exc:
        name, sep, rest = str(exc).partition(": ")
        if sep and name in flags:
            raise InputError(f"{flags[name]}: {rest}") from None
        raise


def at_least(value: float | None, low: float, flag: str) -> None:
    """Reject NaN, infinity and values below ``low``, naming the option."""
    if value is None:
        return
    if not (math.isfinite(value) and value >= low):
        raise InputError(f"{flag}: must be a finite number >= {low:g}, got {value:g}")


def shipped_scenarios() -> list[str]:
    """Names of the scenarios in configs/scenarios."""
    from lrp_gym.config import SCENARIOS_DIR

    return sorted(p.stem for p in SCENARIOS_DIR.glob("*.yaml"))


def load_config(scenario: str, sets: list[str] | None = None, fidelity: str | None = None) -> Any:
    """The scenario with ``--set`` and ``--fidelity`` applied; unknown names get a hint."""
    from lrp_gym.config import load_scenario

    _check_scenario_name(scenario)
    cfg = load_scenario(scenario)
    over = overrides(scenario, sets, fidelity)
    return cfg.with_overrides(over) if over else cfg


def overrides(scenario: str, sets: list[str] | None, fidelity: str | None = None) -> dict:
    """``--set`` and ``--fidelity`` as one override dict, checked against the scenario."""
    from lrp_gym.config import deep_merge

    choice(fidelity, FIDELITIES, "--fidelity")
    _check_scenario_name(scenario)
    out = parse_sets(sets, scenario)
    if fidelity is not None:
        out = deep_merge(out, {"radar": {"fidelity": fidelity}})
    return out


def _check_scenario_name(scenario: str) -> None:
    path = Path(scenario)
    if path.exists() or path.suffix or len(path.parts) > 1:
        return  # a file (the loader reports what is wrong with it)
    names = shipped_scenarios()
    if scenario not in names:
        close = difflib.get_close_matches(scenario, names, n=1, cutoff=0.6)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise InputError(
            f"SCENARIO: no file or shipped scenario {scenario!r}; {hint}shipped: {', '.join(names)}"
        )


def parse_sets(values: list[str] | None, scenario: str | None = None) -> dict[str, Any]:
    """``--set`` options as one nested override dict, checked against the scenario.

    Raises
    ------
    InputError
        A malformed item, naming ``--set``.
    ScenarioError
        A key the schema does not know or a value it rejects, naming the field.
    """
    import yaml

    from lrp_gym.config import deep_merge, load_scenario
    from lrp_gym.scenario_yaml import MAX_YAML_DEPTH, load_yaml

    out: dict[str, Any] = {}
    for item in values or []:
        key, sep, raw = item.partition("=")
        path = key.strip().split(".")
        if not sep or not all(p.strip() for p in path):
            raise InputError(f"--set: expected KEY.PATH=VALUE, got {item!r}")
        if len(path) > MAX_YAML_DEPTH:
            raise InputError(f"--set: the key is nested deeper than {MAX_YAML_DEPTH} levels")
        try:
            value = load_yaml(raw)
        except (yaml.YAMLError, ValueError) as exc:
            raise InputError(f"--set {key}: the value is not valid YAML ({exc})") from None
        for part in reversed(path):
            value = {part.strip(): value}
        out = deep_merge(out, value)
    if out:
        load_scenario(scenario or DEFAULT_SCENARIO).with_overrides(out)  # fail before any work
    return out


def check_output(
    path: str | Path | None,
    flag: str,
    force: bool = False,
    suffixes: Sequence[str] = (),
    directory: bool = False,
) -> Path | None:
    """Check an output path before any work starts; None passes.

    The parent must be (or become) a writable directory, the target must not be a directory
    (unless ``directory``), an existing file is replaced only with ``force``, and a scenario
    shipped in configs/scenarios is never replaced.

    Raises
    ------
    InputError
        Naming ``flag`` and what is wrong.
    """
    from lrp_gym.config import SCENARIOS_DIR

    if path is None:
        return None
    p = Path(path)
    if str(path).strip() == "":
        raise InputError(f"{flag}: empty path")
    if suffixes and not directory and p.suffix.lower() not in suffixes:
        raise InputError(f"{flag}: use a {' or '.join(suffixes)} file name, got {p}")
    if p.exists() and p.resolve().parent == SCENARIOS_DIR.resolve():
        raise InputError(f"{flag}: {p} is a shipped scenario; write to another file")
    if directory:
        if p.exists() and not p.is_dir():
            raise InputError(f"{flag}: {p} is a file, expected a folder")
        _writable_dir(p if p.exists() else _existing_ancestor(p), flag, p)
        return p
    if p.is_dir():
        raise InputError(f"{flag}: {p} is a folder, expected a file name")
    if p.exists() and not force:
        raise InputError(f"{flag}: {p} exists; add --force to replace it")
    _writable_dir(_existing_ancestor(p.parent), flag, p)
    return p


def _existing_ancestor(p: Path) -> Path:
    p = p.absolute()
    while not p.exists():
        p = p.parent
    return p


def _writable_dir(d: Path, flag: str, target: Path) -> None:
    if not d.is_dir():
        raise InputError(f"{flag}: cannot write {target}: {d} is a file, not a folder")
    if not os.access(d, os.W_OK | os.X_OK):
        raise InputError(f"{flag}: cannot write {target}: no write permission in {d}")


def check_random_rooms(n: int) -> None:
    """``--random-rooms N`` (reproduce-paper, evaluate): 0 is off, a negative count an error."""
    if n < 0:
        raise InputError(f"--random-rooms: must not be negative, got {n}")


def check_distinct(*paths: Path | None) -> None:
    """Two outputs of one run must not be the same file."""
    seen: dict[Path, str] = {}
    for p in paths:
        if p is None:
            continue
        key = p.absolute()
        if key in seen:
            raise InputError(f"the same output file is given twice: {p}")
        seen[key] = str(p)


# --------------------------------------------------------------------------- output
def print_json(data: Any) -> None:
    """Print one JSON document to stdout (nothing else goes to stdout with --json)."""
    sys.stdout.write(json.dumps(to_jsonable(data), indent=2) + "\n")
    sys.stdout.flush()


def wrote(path: str | Path, quiet: bool = False) -> None:
    """The one line every command prints per file written (to stderr when stdout is JSON)."""
    (err_console if quiet else console).print(f"wrote {path}", highlight=False, markup=False)


def table(title: str, columns: Sequence[str], left: int = 0) -> Any:
    """A rich table whose headers keep their units: ``[m]`` is escaped, not read as markup.

    The first ``left`` columns are left-aligned, the rest right-aligned; cells fold instead of
    being cut when the terminal is narrow.
    """
    from rich.markup import escape
    from rich.table import Table

    t = Table(title=escape(title))
    for i, col in enumerate(columns):
        t.add_column(escape(col), justify="left" if i < left else "right", overflow="fold")
    return t
