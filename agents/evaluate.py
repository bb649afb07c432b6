"""Deprecated alias of :mod:`agents.registry` (the agents by name); docs before 0.2 named it."""

import warnings

from agents.registry import *  # noqa: F403
from agents.registry import __all__  # noqa: F401

warnings.warn("agents.evaluate is now agents.registry", DeprecationWarning, stacklevel=2)
