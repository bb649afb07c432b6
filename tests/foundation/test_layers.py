"""Imports point one way: every module imports only its own layer or lower ones.

A small AST walk over every module of ``lrp_gym`` and ``agents``. Imports inside functions
count like top-level ones (a lazy import is still a dependency); imports under
``if TYPE_CHECKING:`` never run, so they only have to respect the two hard walls (the library
never imports ``agents``, ``agents`` never imports the CLI), not the layer order.
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

#: Bottom to top. A module belongs to the layer of the longest prefix that names it.
LAYERS: tuple[tuple[str, ...], ...] = (
    # Physical constants and waveform numbers, errors, file output: depend on nothing here.
    ("lrp_gym.errors", "lrp_gym.waveform", "lrp_gym.output", "lrp_gym.scenario_yaml"),
    ("lrp_gym.world",),
    # The schema checks a scenario against the world's geometry (config/checks.py), so it sits
    # above the world; the world reads a config only as a type (TYPE_CHECKING).
    ("lrp_gym.config",),
    ("lrp_gym.radar",),
    ("lrp_gym.tracking",),
    ("lrp_gym.localization",),
    ("lrp_gym.placement", "lrp_gym.perturbations"),
    # The package itself registers the env ids on import.
    ("lrp_gym.envs", "lrp_gym"),
    ("lrp_gym.experiments",),
    # The CLI: the one place where lrp_gym and agents meet.
    ("lrp_gym.commands", "lrp_gym.cli"),
)
CLI = ("lrp_gym.commands", "lrp_gym.cli")


@dataclass(frozen=True)
class Import:
    module: str  # the importing module
    target: str  # the imported module (lrp_gym.* or agents.*)
    line: int
    type_only: bool  # under ``if TYPE_CHECKING:``


def _within(name: str, prefix: str) -> bool:
    return name == prefix or name.startswith(prefix + ".")


def layer_of(module: str) -> int:
    best, index = "", -1
    for i, prefixes in enumerate(LAYERS):
        for p in prefixes:
            # "lrp_gym" alone is the package __init__, not everything under it.
            ok = module == p if p == "lrp_gym" else _within(module, p)
            if ok and len(p) > len(best):
                best, index = p, i
    if index < 0:
        raise LookupError(f"{module} is in no layer: add it to LAYERS in {__file__}")
    return index


def _module_name(path: Path, root: Path) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _is_module(name: str, root: Path) -> bool:
    p = root.joinpath(*name.split("."))
    return p.with_suffix(".py").is_file() or (p / "__init__.py").is_file()


def imports_of(source: str, module: str, is_package: bool, root: Path) -> list[Import]:
    """The project-internal imports of one module's source."""
    tree = ast.parse(source)
    type_only: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            type_only.update(id(n) for stmt in node.body for n in ast.walk(stmt))
    out = []
    for node in ast.walk(tree):
        targets: list[str] = []
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                pkg = module.split(".") if is_package else module.split(".")[:-1]
                pkg = pkg[: len(pkg) - (node.level - 1)]
                base = ".".join(pkg + ([base] if base else []))
            # ``from pkg import sub`` depends on pkg.sub when sub is a module.
            subs = [f"{base}.{a.name}" for a in node.names if _is_module(f"{base}.{a.name}", root)]
            targets = subs or [base]
        for t in targets:
            if t.split(".")[0] in ("lrp_gym", "agents"):
                out.append(Import(module, t, node.lineno, id(node) in type_only))
    return out


def all_imports(root: Path = ROOT) -> list[Import]:
    out = []
    for pkg in ("lrp_gym", "agents"):
        for path in sorted((root / pkg).rglob("*.py")):
            name = _module_name(path, root)
            out += imports_of(path.read_text(), name, path.name == "__init__.py", root)
    return out


def violations(imports: list[Import]) -> list[str]:
    """One line per import that breaks a rule."""
    bad = []
    for imp in imports:
        where = f"{imp.module}:{imp.line} imports {imp.target}"
        in_cli = any(_within(imp.module, c) for c in CLI)
        if _within(imp.module, "agents"):
            if any(_within(imp.target, c) for c in CLI):
                bad.append(f"{where}: agents never import the CLI")
            continue
        if _within(imp.target, "agents"):
            if not in_cli:
                bad.append(f"{where}: only the CLI imports agents (pass policies in)")
            continue
        if imp.type_only:
            continue
        if layer_of(imp.target) > layer_of(imp.module):
            bad.append(f"{where}: a lower layer imports a higher one")
    return bad


def test_every_module_has_a_layer():
    for imp in all_imports():
        if imp.module.startswith("lrp_gym"):
            layer_of(imp.module)


def test_imports_point_one_way():
    bad = violations(all_imports())
    assert not bad, "\n".join(bad)


# The checker itself, on made-up sources: it must catch what it claims to catch.
@pytest.mark.parametrize(
    ("module", "source", "rule"),
    [
        ("lrp_gym.world.room", "from lrp_gym.radar.sensor import RadarSensor", "lower layer"),
        ("lrp_gym.radar.sensor", "def f():\n    from lrp_gym.localization import amcl", "lower"),
        ("lrp_gym.experiments.x", "import agents.registry", "only the CLI imports agents"),
        ("lrp_gym.envs.x", "if TYPE_CHECKING:\n    from agents import ppo", "only the CLI"),
        ("agents.ppo", "from lrp_gym.commands._common import table", "never import the CLI"),
    ],
)
def test_checker_catches_a_wrong_import(module, source, rule):
    bad = violations(imports_of(source, module, False, ROOT))
    assert len(bad) == 1 and rule in bad[0]


@pytest.mark.parametrize(
    ("module", "source"),
    [
        ("lrp_gym.localization.amcl", "from lrp_gym.world.room import Room"),
        ("lrp_gym.world.world", "if TYPE_CHECKING:\n    from lrp_gym.config import ScenarioConfig"),
        ("lrp_gym.commands.evaluate", "from agents.registry import make_agent"),
        ("agents.pure_pursuit", "from lrp_gym.envs.observations import EstimatedPoseObservation"),
        ("lrp_gym.radar.cfar", "from . import processing"),
    ],
)
def test_checker_lets_a_right_import_pass(module, source):
    assert violations(imports_of(source, module, False, ROOT)) == []


def test_relative_imports_resolve_to_the_module():
    imps = imports_of("from ..world import room", "lrp_gym.radar.channel", False, ROOT)
    assert [i.target for i in imps] == ["lrp_gym.world.room"]


def cli_flag_strings(source: str) -> list[tuple[int, str]]:
    """Messages (f-string parts included) that start by naming a CLI flag: ``"--name: ..."``."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            m = re.match(r"(--[a-z][\w-]*)(:| [a-z]+ *:)", node.value)
            if m:
                out.append((node.lineno, m.group(1)))
    return out


FLAG_EXCEPTIONS: tuple[str, ...] = ()


def test_only_the_cli_knows_its_flags():
    bad = []
    for pkg in ("lrp_gym", "agents"):
        for path in sorted((ROOT / pkg).rglob("*.py")):
            name = _module_name(path, ROOT)
            if any(_within(name, c) for c in CLI) or name in FLAG_EXCEPTIONS:
                continue
            bad += [f"{name}:{line} {flag}" for line, flag in cli_flag_strings(path.read_text())]
    assert not bad, "library code names CLI flags (raise ValueError naming the argument):\n" + (
        "\n".join(bad)
    )


def test_flag_finder_sees_plain_and_formatted_strings():
    src = 'raise E("--model: no file")\nraise E(f"--episodes: {n}")\nplot(ls="--")\nh = "--help"'
    assert [f for _, f in cli_flag_strings(src)] == ["--model", "--episodes"]
