"""Shared test fixtures."""

from __future__ import annotations

import os

import matplotlib
import pytest

matplotlib.use("Agg")
os.environ.setdefault("MPLBACKEND", "Agg")

from lrp_gym.config import SCENARIOS_DIR, load_scenario  # noqa: E402


@pytest.fixture(scope="session")
def paper_cfg():
    """The paper's proof-of-concept scenario."""
    return load_scenario(SCENARIOS_DIR / "ipin2023.yaml")


@pytest.fixture(scope="session")
def paper_world(paper_cfg):
    from lrp_gym.world import World

    return World.from_config(paper_cfg)
