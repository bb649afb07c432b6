"""Scenario schema: round trip, error messages, cross-field checks, fuzzing."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lrp_gym.config import (
    SCENARIOS_DIR,
    LocalizationConfig,
    RadarConfig,
    RobotConfig,
    RoomConfig,
    ScenarioConfig,
    ScenarioError,
    TaskConfig,
    TrackingConfig,
    load_scenario,
    save_scenario,
)

PAPER = SCENARIOS_DIR / "ipin2023.yaml"


def paper_dict() -> dict:
    return yaml.safe_load(PAPER.read_text())


def problems_of(data) -> list[str]:
    with pytest.raises(ScenarioError) as info:
        ScenarioConfig.from_dict(data)
    return info.value.problems


@pytest.mark.parametrize("name", sorted(p.stem for p in SCENARIOS_DIR.glob("*.yaml")))
def test_shipped_scenarios_round_trip(name, tmp_path):
    cfg = load_scenario(name)
    out = save_scenario(cfg, tmp_path / "copy.yaml", header="round trip")
    again = load_scenario(out)
    assert again == cfg
    assert again.to_dict() == cfg.to_dict()


def test_dict_round_trip_is_lossless():
    cfg = ScenarioConfig.from_dict(paper_dict())
    assert ScenarioConfig.from_dict(cfg.to_dict()) == cfg


def test_code_defaults_agree_with_paper_scenario():
    """Where ipin2023.yaml and the code defaults overlap they must say the same."""
    cfg = load_scenario(PAPER)
    assert cfg.radar == RadarConfig()
    assert cfg.tracking == TrackingConfig()
    assert cfg.localization == LocalizationConfig()
    assert cfg.room == RoomConfig()
    assert cfg.robot.model_dump(exclude={"start_pose"}) == RobotConfig().model_dump(
        exclude={"start_pose"}
    )
    assert cfg.task.frame_period_s == TaskConfig(mode="goal").frame_period_s


def test_room_size_message_names_field_and_value():
    data = paper_dict()
    data["room"]["size"] = [5, -1, 4]
    assert "room.size: expected 3 positive numbers, got [5, -1, 4]" in problems_of(data)


def test_all_problems_reported_at_once():
    data = paper_dict()
    data["room"]["size"] = [5, -1, 4]
    data["radar"]["window"] = "kaiser"
    data["radar"]["bogus"] = 1
    data["localization"] = {"initial_particles": -5}
    probs = problems_of(data)
    joined = "\n".join(probs)
    assert len(probs) >= 4
    for field in ("room.size", "radar.window", "radar.bogus", "localization.initial_particles"):
        assert field in joined


@pytest.mark.parametrize(
    ("patch", "expected"),
    [
        (
            {"reflectors": {"layout": [{"position": [6, 1, 3], "type": "A"}]}},
            "reflectors.layout[0].position: [6, 1, 3] is outside the room",
        ),
        (
            {"reflectors": {"layout": [{"position": [1, 1, 3], "type": "Z"}]}},
            "'Z' is not one of the types",
        ),
        (
            {
                "robot": {"start_pose": [2.5, 2.5, 0]},
                "room": {"obstacles": [{"min": [2, 2, 0], "max": [3, 3, 1]}]},
            },
            "robot.start_pose: the robot (robot.radius_m 0.2 m) at [2.5, 2.5] overlaps",
        ),
        (
            {"task": {"path": [[1, 1], [7, 1]]}},
            "task.path[1]: the robot (robot.radius_m 0.2 m) at waypoint [7, 1]",
        ),
        ({"radar": {"samples_per_chirp": 64}}, "does not cover the room diagonal"),
        ({"radar": {"chirp_period_s": 0.002}}, "unambiguous velocity"),
        (
            {"room": {"obstacles": [{"min": [1, 1, 0], "max": [0.5, 2, 1]}]}},
            "room.obstacles[0]: min [1, 1, 0] must be below max [0.5, 2, 1]",
        ),
        ({"reflectors": {"types": {"B": {"kind": "trihedral"}}}}, "kind trihedral needs edge_m"),
        ({"radar": {"cfar": {"training_cells": [200, 3]}}}, "cfar window"),
        ({"unexpected": 1}, "unexpected: unknown key"),
        ({"tracking": {"confirm_hits": 5, "confirm_window": 3}}, "confirm_hits (5)"),
        ({"radar": {"noise": "maybe"}}, "radar.noise"),
        ({"robot": {"start_pose": [1, 1]}}, "robot.start_pose: expected 3 numbers"),
    ],
)
def test_each_validation_error_is_clear(patch, expected):
    from lrp_gym.config import deep_merge

    data = deep_merge(paper_dict(), patch)
    joined = "\n".join(problems_of(data))
    assert expected in joined


def test_reflector_inside_obstacle_is_rejected():
    data = paper_dict()
    x, y, z = data["reflectors"]["layout"][0]["position"]
    data["room"]["obstacles"] = [
        {"min": [x - 0.1, y - 0.1, z - 0.5], "max": [x + 0.1, y + 0.1, z + 0.5]}
    ]
    assert any("inside an obstacle" in p for p in problems_of(data))


def test_non_mapping_and_bad_yaml(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("room: [unclosed\n")
    with pytest.raises(ScenarioError, match="cannot read YAML"):
        load_scenario(bad)
    listy = tmp_path / "list.yaml"
    listy.write_text("- 1\n- 2\n")
    with pytest.raises(ScenarioError, match="expected a mapping"):
        load_scenario(listy)
    with pytest.raises(ScenarioError, match="file not found"):
        load_scenario(tmp_path / "missing.yaml")


def test_requirements_derive_the_waveform():
    data = paper_dict()
    data["radar"]["requirements"] = {
        "range_resolution_m": 0.075,
        "max_range_m": 19.0,
        "velocity_resolution_mps": 0.36,
        "max_velocity_mps": 5.6,
    }
    fm = ScenarioConfig.from_dict(data).fmcw()
    assert fm.range_resolution_m == pytest.approx(0.075)
    assert fm.max_range_m >= 19.0
    assert fm.velocity_resolution_mps <= 0.36 + 1e-12
    assert fm.max_velocity_mps == pytest.approx(5.6)


def test_with_overrides_merges_nested_keys():
    cfg = load_scenario(PAPER).with_overrides({"radar": {"noise": False}})
    assert cfg.radar.noise is False
    assert cfg.radar.bandwidth_hz == 2e9


# --- fuzzing: valid configs load, invalid ones give ScenarioError, nothing else escapes ------
_leaf = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-10, 10**6),
    st.floats(allow_nan=True),
    st.text(max_size=6),
    st.lists(st.floats(-10, 10), max_size=4),
)


@st.composite
def mutated(draw):
    data = paper_dict()
    paths = [
        ("room", "size"),
        ("radar", "bandwidth_hz"),
        ("radar", "samples_per_chirp"),
        ("radar", "cfar", "pfa"),
        ("radar", "window"),
        ("robot", "start_pose"),
        ("localization", "initial_particles"),
        ("task", "path"),
        ("reflectors", "layout"),
        ("reflectors", "types"),
        ("tracking", "confirm_hits"),
        ("task", "frame_period_s"),
        ("room", "obstacles"),
        ("radar",),
        ("name",),
    ]
    for path in draw(st.lists(st.sampled_from(paths), min_size=1, max_size=3)):
        node = data
        for key in path[:-1]:
            if not isinstance(node.get(key), dict):
                node[key] = {}  # an earlier mutation may have replaced the section
            node = node[key]
        node[path[-1]] = draw(_leaf)
    return data


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_fuzzed_configs_never_raise_anything_but_scenario_error(data):
    try:
        cfg = ScenarioConfig.from_dict(copy.deepcopy(data))
    except ScenarioError as exc:
        assert exc.problems and all(isinstance(p, str) and p for p in exc.problems)
    else:
        assert ScenarioConfig.from_dict(cfg.to_dict()) == cfg


@settings(max_examples=60, deadline=None)
@given(
    size=st.tuples(*(st.floats(3.0, 12.0) for _ in range(3))),
    frac=st.lists(st.tuples(st.floats(0.05, 0.95), st.floats(0.05, 0.95)), min_size=1, max_size=6),
)
def test_random_valid_configs_load(size, frac):
    lx, ly, lz = size
    layout = [{"position": [fx * lx, fy * ly, 0.7 * lz], "type": "A"} for fx, fy in frac]
    data = {
        "room": {"size": list(size)},
        "reflectors": {"layout": layout},
        "robot": {"start_pose": [lx / 2, ly / 2, 0.0]},
        "radar": {"samples_per_chirp": 512},
    }
    cfg = ScenarioConfig.from_dict(data)
    assert np.allclose(cfg.room.size, size)
    assert len(cfg.reflectors.layout) == len(frac)
