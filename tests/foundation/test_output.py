"""Whole-file outputs: written whole, and readable like any file the user writes."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from lrp_gym.output import atomic_path, write_json


def test_an_output_gets_the_mode_a_plain_open_gives(tmp_path: Path) -> None:
    plain = tmp_path / "plain.txt"
    plain.write_text("x")
    out = write_json({"a": 1}, tmp_path / "out.json")
    # mkstemp alone would leave 0600: other users (and CI artefact steps) could not read it.
    assert os.stat(out).st_mode & 0o777 == os.stat(plain).st_mode & 0o777
    assert json.loads(out.read_text()) == {"a": 1}


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path: Path) -> None:
    target = tmp_path / "result.json"
    write_json({"old": True}, target)
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("{half")
        raise RuntimeError("interrupted")
    assert json.loads(target.read_text()) == {"old": True}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["result.json"]
