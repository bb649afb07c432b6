"""Shared pieces of the schema: the shipped configs folder, the error type, value formats."""

from __future__ import annotations

import importlib.resources
import math
from pathlib import Path
from typing import Annotated, Any

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
)
from pydantic_core import PydanticCustomError


def _configs_dir() -> Path:
    """The shipped configs: package data of an installed wheel, else the checkout's configs/.

    The wheel copies the top-level ``configs/`` into ``lrp_gym/configs`` (see pyproject.toml),
    so there is one copy to edit; editable installs and source checkouts read it in place.
    """
    packaged = Path(str(importlib.resources.files("lrp_gym") / "configs"))
    return packaged if packaged.is_dir() else Path(__file__).resolve().parents[2] / "configs"


CONFIGS_DIR = _configs_dir()
SCENARIOS_DIR = CONFIGS_DIR / "scenarios"


class ScenarioError(ValueError):
    """A scenario failed validation; ``problems`` lists one message per bad field."""

    def __init__(self, problems: list[str], source: str | None = None) -> None:
        self.problems = problems
        self.source = source
        head = f"invalid scenario{f' {source}' if source else ''}"
        super().__init__(head + ":\n" + "\n".join(f"  - {p}" for p in problems))


def _fmt(value: Any) -> str:
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_fmt(v) for v in value) + "]"
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return repr(value) if isinstance(value, str) else str(value)


def _vector(n: int, positive: bool = False, what: str = "numbers"):
    """A list of ``n`` finite floats, with a message that shows what was given."""

    def check(value: Any) -> list[float]:
        kind = f"{n} positive {what}" if positive else f"{n} {what}"
        ok = isinstance(value, (list, tuple)) and len(value) == n
        if ok:
            try:
                out = [float(v) for v in value]
            except (TypeError, ValueError):
                ok = False
            else:
                if any(isinstance(v, bool) for v in value) or not all(map(math.isfinite, out)):
                    ok = False
                elif positive and any(v <= 0 for v in out):
                    ok = False
        if not ok:
            raise PydanticCustomError(
                "vector", "expected {kind}, got {got}", {"kind": kind, "got": _fmt(value)}
            )
        return out

    from pydantic import BeforeValidator

    return Annotated[list[float], BeforeValidator(check)]


Vec2 = _vector(2)
Vec3 = _vector(3)
PosVec3 = _vector(3, positive=True)
Pose = _vector(3, what="numbers (x_m, y_m, theta_rad)")
PositiveFloat = Annotated[float, Field(gt=0, allow_inf_nan=False)]
NonNegFloat = Annotated[float, Field(ge=0, allow_inf_nan=False)]
Probability = Annotated[float, Field(gt=0, lt=1, allow_inf_nan=False)]
Fraction = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_default=True)
