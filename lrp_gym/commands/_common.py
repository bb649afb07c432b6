"""Helpers shared by the subcommands."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console

console = Console()

ScenarioArg = "Scenario YAML file, or the name of one in configs/scenarios (e.g. ipin2023)."
SetHelp = (
    "Override a scenario setting, KEY.PATH=VALUE (the value is read as YAML), e.g. "
    "localization.measurements=tracks; repeatable."
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
    from lrp_gym.errors import InputError
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
        load_scenario(scenario or "ipin2023").with_overrides(out)  # fail before any work
    return out


def to_jsonable(value: Any) -> Any:
    """Numpy scalars and arrays to plain Python; NaN and inf to None (valid JSON)."""
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, (np.floating, float)):
        f = float(value)
        return f if math.isfinite(f) else None
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def print_json(data: Any) -> None:
    """Print one JSON document to stdout (nothing else goes to stdout with --json)."""
    sys.stdout.write(json.dumps(to_jsonable(data), indent=2) + "\n")
    sys.stdout.flush()


def write_json(data: Any, path: str | Path) -> Path:
    """Write JSON atomically: a temporary file renamed into place, so the output is whole."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(to_jsonable(data), indent=2) + "\n", encoding="utf-8")
    tmp.replace(path)
    return path


def save_figure(fig, path: str | Path) -> Path:
    """Save a matplotlib figure atomically and close it."""
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.stem + ".tmp" + path.suffix)
    fig.savefig(tmp, dpi=120, bbox_inches="tight")
    plt.close(fig)
    tmp.replace(path)
    return path
