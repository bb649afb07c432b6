"""The wheel is complete: built from a clean copy, installed into a fresh venv outside the repo,
it registers the env with its scenarios, runs the demo and evaluates the shipped PPO model."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SKIP = {".git", ".venv", "build", "dist", "runs", "outputs", "logs", "__pycache__"}


def test_every_package_is_listed_in_pyproject():
    """pyproject lists packages by hand (configs/ is mapped in): a new one must be added."""
    block = re.search(r"^packages = \[(.*?)\]", (REPO / "pyproject.toml").read_text(), re.S | re.M)
    listed = set(re.findall(r'"([\w.]+)"', block.group(1)))
    found = {
        ".".join(p.parent.relative_to(REPO).parts)
        for top in ("lrp_gym", "agents")
        for p in (REPO / top).rglob("__init__.py")
    }
    assert found <= listed, sorted(found - listed)


def _run(argv, **kw):
    res = subprocess.run(argv, capture_output=True, text=True, timeout=600, **kw)
    assert res.returncode == 0, f"{argv}\n{res.stdout[-2000:]}\n{res.stderr[-3000:]}"
    return res.stdout


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    # A clean copy: an in-tree build/ could carry stale files into the wheel.
    src = tmp_path_factory.mktemp("src") / "lrp-gym"
    shutil.copytree(
        REPO,
        src,
        ignore=lambda d, names: [n for n in names if n in SKIP or n.endswith(".egg-info")],
    )
    dist = tmp_path_factory.mktemp("dist")
    _run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            str(src),
            "--no-deps",
            "--no-build-isolation",
            "-w",
            str(dist),
            "-q",
        ]
    )
    return next(dist.glob("lrp_gym-*.whl"))


def test_wheel_holds_scenarios_config_model_and_py_typed(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    for name in (
        "lrp_gym/py.typed",
        "lrp_gym/configs/ppo.yaml",
        "lrp_gym/configs/scenarios/ipin2023.yaml",
        "agents/models/ppo_lrp_nav.zip",
        "agents/models/vecnormalize.json",
    ):
        assert name in names, name
    assert not [n for n in names if n.endswith(".pkl")]


@pytest.mark.integration
@pytest.mark.timeout(900)
def test_installed_wheel_works_outside_the_repo(wheel, tmp_path):
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", str(venv)])
    py = venv / "bin" / "python"
    site = Path(
        _run([str(py), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"]).strip()
    )
    # Dependencies (torch, SB3, ...) come from the test venv: a .pth line puts its
    # site-packages *after* the new venv's own, so the wheel's lrp_gym wins. (.pth files in
    # that directory, such as the editable install's, are not processed from there.)
    (site / "zz_deps.pth").write_text(sysconfig.get_path("purelib") + "\n")
    _run([str(py), "-m", "pip", "install", "--no-deps", "-q", str(wheel)])
    work = tmp_path / "elsewhere"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    check = (
        "import gymnasium as gym, lrp_gym, agents.ppo_config as c; "
        "print(lrp_gym.__file__); print(c.DEFAULT_CONFIG); "
        "e = gym.make('LRPRadarNav-v0'); e.reset(seed=0); print(e.observation_space.shape)"
    )
    out = _run([str(py), "-c", check], cwd=work, env=env).splitlines()
    assert out[0].startswith(str(site)), out  # the installed wheel, not the checkout
    assert out[1].startswith(str(site)) and out[2] == "(20,)", out
    lrp = venv / "bin" / "lrp-gym"
    _run([str(lrp), "demo", "--steps", "3", "--out", str(work / "demo")], cwd=work, env=env)
    assert (work / "demo" / "summary.json").is_file()
    out = _run(
        [str(lrp), "evaluate", "--agent", "ppo", "--episodes", "1", "--json"], cwd=work, env=env
    )
    assert '"episodes": 1' in out and str(site) in out
