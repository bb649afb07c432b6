"""The whole scenario: sections, cross-field checks, loading, saving and overrides."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml
from pydantic import (
    ValidationError,
    model_validator,
)
from pydantic_core import PydanticCustomError

from lrp_gym.config.base import SCENARIOS_DIR, ScenarioError, Strict, _fmt
from lrp_gym.config.checks import cross_problems
from lrp_gym.config.localization import LocalizationConfig
from lrp_gym.config.perturbations import PerturbationsConfig
from lrp_gym.config.radar import RadarConfig
from lrp_gym.config.robot import RobotConfig
from lrp_gym.config.room import ReflectorsConfig, RoomConfig
from lrp_gym.config.task import EnvConfig, PlacementConfig, TaskConfig
from lrp_gym.config.tracking import TrackingConfig
from lrp_gym.scenario_yaml import load_yaml
from lrp_gym.waveform import FmcwParameters


class ScenarioConfig(Strict):
    """A complete scenario. Every section has defaults; ``reflectors.layout`` must be given."""

    name: str = "scenario"
    description: str = ""
    room: RoomConfig = RoomConfig()
    reflectors: ReflectorsConfig = ReflectorsConfig()
    radar: RadarConfig = RadarConfig()
    robot: RobotConfig = RobotConfig()
    tracking: TrackingConfig = TrackingConfig()
    localization: LocalizationConfig = LocalizationConfig()
    placement: PlacementConfig = PlacementConfig()
    task: TaskConfig = TaskConfig(mode="goal")
    env: EnvConfig = EnvConfig()
    perturbations: PerturbationsConfig = PerturbationsConfig()

    @model_validator(mode="after")
    def _cross_checks(self) -> ScenarioConfig:
        problems = list(cross_problems(self))
        if problems:
            raise PydanticCustomError("cross", "\n".join(problems), {})
        return self

    # --- construction ------------------------------------------------------------
    @classmethod
    def from_dict(cls, data: Any, source: str | None = None) -> ScenarioConfig:
        """Validate a mapping; raise :class:`ScenarioError` listing every problem."""
        if not isinstance(data, dict):
            raise ScenarioError(
                [f"expected a mapping at the top level, got {type(data).__name__}"], source
            )
        try:
            return cls.model_validate(data)
        except ValidationError as exc:
            raise ScenarioError(format_errors(exc), source) from None

    def to_dict(self) -> dict[str, Any]:
        return self.model_dump(mode="json", exclude_none=True)

    def with_overrides(self, overrides: dict[str, Any]) -> ScenarioConfig:
        """A copy with nested keys replaced, e.g. ``{"radar": {"noise": False}}``."""
        return ScenarioConfig.from_dict(deep_merge(self.to_dict(), overrides), self.name)

    # --- derived runtime objects -----------------------------------------------------
    def fmcw(self) -> FmcwParameters:
        return self.radar.fmcw()


def deep_merge(base: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """Recursively merge ``overrides`` into a copy of ``base`` (dicts merge, others replace)."""
    out = dict(base)
    for key, value in overrides.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = deep_merge(out[key], value)
        else:
            out[key] = value
    return out


def format_errors(exc: ValidationError) -> list[str]:
    """One ``field.path: message`` line per validation problem."""
    problems: list[str] = []
    for err in exc.errors():
        loc = ".".join(f"[{p}]" if isinstance(p, int) else str(p) for p in err["loc"]).replace(
            ".[", "["
        )
        msg = err["msg"]
        if err["type"] == "extra_forbidden":
            msg = "unknown key (not part of the schema)"
        elif err["type"] == "missing":
            msg = "required field is missing"
        elif err["type"] == "literal_error":
            msg = f"{msg}, got {_fmt(err.get('input'))}"
        elif (
            err["type"] not in {"vector", "box", "reflector", "cells", "cross", "choice"}
            and "input" in err
        ):
            got = err["input"]
            if not isinstance(got, (dict, list)):
                msg = f"{msg}, got {_fmt(got)}"
        if err["type"] == "cross":
            problems.extend(msg.split("\n"))
            continue
        problems.append(f"{loc}: {msg}" if loc else msg)
    return problems


def load_scenario(source: str | Path | dict[str, Any] | ScenarioConfig) -> ScenarioConfig:
    """Load and validate a scenario.

    Parameters
    ----------
    source : path, name, dict or ScenarioConfig
        A YAML file, the name of a scenario shipped in ``configs/scenarios`` (e.g.
        ``"ipin2023"``), a mapping, or an already validated config.

    Raises
    ------
    ScenarioError
        With one message per problem, each naming the field.
    """
    if isinstance(source, ScenarioConfig):
        return source
    if isinstance(source, dict):
        return ScenarioConfig.from_dict(source)
    path = Path(source)
    if not path.exists() and not path.suffix and (SCENARIOS_DIR / f"{path}.yaml").exists():
        path = SCENARIOS_DIR / f"{path}.yaml"
    if not path.exists():
        raise ScenarioError([f"file not found: {path}"], str(path))
    if path.is_dir():
        raise ScenarioError([f"expected a YAML file, got a directory: {path}"], str(path))
    if not path.is_file():  # a FIFO or device would block or never end
        raise ScenarioError(
            [f"expected a regular YAML file, got a special file: {path}"], str(path)
        )
    try:
        data = load_yaml(path.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError, OSError) as exc:
        raise ScenarioError([f"cannot read YAML: {exc}".replace("\n", " ")], str(path)) from None
    except ValueError as exc:
        raise ScenarioError([f"cannot read YAML: {exc}"], str(path)) from None
    return ScenarioConfig.from_dict(data, str(path))


def save_scenario(cfg: ScenarioConfig, path: str | Path, header: str = "") -> Path:
    """Write a scenario as YAML atomically (a temporary file renamed into place)."""
    path = Path(path)
    text = yaml.safe_dump(cfg.to_dict(), sort_keys=False, default_flow_style=None, width=100)
    if header:
        text = "".join(f"# {line}\n" if line else "#\n" for line in header.splitlines()) + text
    tmp = path.with_name(path.name + ".tmp")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)
    return path
