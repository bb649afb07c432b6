"""Scenarios that used to validate and then crash (or run physically wrong) are now rejected.

One case per row of issue #13's table: each ``--set`` override must make every command that
takes a scenario exit with code 2 and a message naming the field, before any work is done.
"""

from __future__ import annotations

import os
import warnings

import numpy as np
import pytest
from gymnasium.error import ResetNeeded

from lrp_gym.cli import main
from lrp_gym.config import ScenarioError, load_scenario
from lrp_gym.scenario_yaml import load_yaml

BOX = "{min: [2, 2, 0], max: [3, 3, 1]}"
ROWS = [
    # goal-distance bounds: min above max, and min beyond any two free positions of the room
    (["task.goal.min_distance_m=3", "task.goal.max_distance_m=1"], "task.goal.min_distance_m"),
    (
        ["task.mode=goal", "task.goal.min_distance_m=8", "task.goal.max_distance_m=20"],
        "task.goal.min_distance_m",
    ),
    # the robot's radius against walls and obstacles (start and waypoints as discs)
    (["robot.radius_m=2.4"], "robot.radius_m"),
    (["task.mode=goal", "room.obstacles=[{min: [0.1, 0, 0], max: [5, 5, 1]}]"], "robot.radius_m"),
    (["task.path=[[0.75, 0.75], [0.75, 0.75]]"], "task.path"),
    (["env.observation.type=bogus"], "env.observation.type"),
    # a leg through a box whose waypoints lie outside it
    (["task.path=[[0.75, 0.75], [4, 4]]", f"room.obstacles=[{BOX}]"], "task.path[0]..[1]"),
    (["robot.start_pose=[0.1, 0.75, 0]"], "robot.start_pose"),
    (["task.frame_period_s=1e6"], "task.frame_period_s"),
    # the default axis points from the reflector to itself: NaN
    (
        [
            "reflectors.layout=[{position: [2.5, 2.5, 0.3], type: A}, {position: [1, 1, 3], type: A}]"
        ],
        "reflectors.layout[0].axis",
    ),
    (["localization.initial_particles=10"], "localization.initial_particles"),
]


def _sets(items: list[str]) -> list[str]:
    return [arg for item in items for arg in ("--set", item)]


def _rejected(args: list[str], field: str, capsys) -> None:
    with pytest.raises(SystemExit) as exc:
        main(args)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert field in err and "Traceback" not in err


@pytest.mark.parametrize(("items", "field"), ROWS, ids=[r[1] + str(i) for i, r in enumerate(ROWS)])
def test_row_is_rejected_with_exit_2_naming_the_field(items, field, capsys):
    _rejected(["validate", "ipin2023", *_sets(items)], field, capsys)


@pytest.mark.parametrize(
    "command", [["reproduce-paper"], ["evaluate"], ["robustness"], ["track", "ipin2023"]]
)
@pytest.mark.parametrize("row", [2, 6, 9])
def test_every_command_rejects_the_rows_before_running(command, row, capsys):
    items, field = ROWS[row]
    _rejected([*command, *_sets(items)], field, capsys)


def test_radar_range_shorter_than_the_room_is_rejected():
    with pytest.raises(ScenarioError, match="does not cover the room diagonal"):
        load_scenario("ipin2023").with_overrides(
            {"radar": {"bandwidth_hz": 4e9, "samples_per_chirp": 128}}
        )


def test_unused_reflector_type_is_allowed_and_changes_nothing():
    """A catalogue type without reflectors: no detection may be it, so the run is identical."""
    from lrp_gym.experiments.reproduce import reproduce

    over = {
        "task": {"path": [[0.75, 0.75], [1.75, 0.75], [1.75, 1.75]]},
        "localization": {
            "initial_particles": 300,
            "max_particles": 300,
            "min_particles": 100,
            "lut_grid_m": 0.1,
            "lut_resolution_m": 0.1,
        },
        "radar": {"fidelity": "detections"},
    }
    base = load_scenario("ipin2023").with_overrides(over)
    sphere = {"kind": "sphere", "diameter_m": 0.1}
    cat = base.with_overrides({"reflectors": {"types": {"B": sphere}}})
    a, b = reproduce(base, runs=1, seed=3), reproduce(cat, runs=1, seed=3)
    np.testing.assert_array_equal(a.amcl_errors_m, b.amcl_errors_m)
    np.testing.assert_array_equal(a.lut_errors_m, b.lut_errors_m)


# --------------------------------------------------------------------------- YAML files
@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("name: a\nname: b\n", "duplicate key 'name'"),
        ("room: {size: [5, 5, 4], size: [6, 6, 4]}\n", "duplicate key 'size'"),
        ("a: " + "[" * 1000 + "]" * 1000 + "\n", "nested deeper"),
    ],
)
def test_yaml_duplicates_and_deep_nesting_give_clear_errors(tmp_path, capsys, text, message):
    path = tmp_path / "s.yaml"
    path.write_text(text)
    with pytest.raises(SystemExit) as exc:
        main(["validate", str(path)])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert message in err and "RecursionError" not in err


def test_a_fifo_is_refused_before_reading(tmp_path):
    fifo = tmp_path / "s.yaml"
    os.mkfifo(fifo)  # opening it for reading would block forever
    with pytest.raises(ScenarioError, match="regular YAML file"):
        load_scenario(fifo)


def test_set_values_go_through_the_same_loader():
    assert load_yaml("{a: 1, b: [1, 2]}") == {"a": 1, "b": [1, 2]}
    with pytest.raises(SystemExit) as exc:
        main(["validate", "ipin2023", "--set", "robot={radius_m: 0.2, radius_m: 0.3}"])
    assert exc.value.code == 2


# --------------------------------------------------------------------------- env order
def _env(**over):
    from lrp_gym.envs.nav_env import LRPRadarNavEnv

    base = {"localization": {"initial_particles": 200, "max_particles": 200}}
    return LRPRadarNavEnv("ipin2023", {**base, **over}, radar_fidelity="detections")


def test_step_and_render_before_reset_say_call_reset_first():
    env = _env()
    with pytest.raises(ResetNeeded, match=r"call reset\(\) first"):
        env.step(np.zeros(2))
    env.render_mode = "rgb_array"
    with pytest.raises(ResetNeeded, match=r"call reset\(\) first"):
        env.render()


def test_stepping_after_termination_pays_nothing_until_reset():
    # Start facing the wall at x = 0, 0.3 m away: full speed collides in the first step.
    env = _env(robot={"start_pose": [0.3, 0.75, np.pi]})
    env.reset(seed=0)
    _, reward, terminated, _, info = env.step(np.array([1.0, 0.0]))
    assert terminated and info["collision"] and reward < -4.0
    pose = env.pose.copy()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        obs, reward, terminated, _, info = env.step(np.array([1.0, 0.0]))
    assert reward == 0.0 and terminated and not info["collision"]
    assert any("reset()" in str(w.message) for w in caught)
    np.testing.assert_array_equal(env.pose, pose)
    env.reset(seed=1)
    _, reward, terminated, _, _ = env.step(np.array([0.0, 0.0]))
    assert not terminated and reward == pytest.approx(-0.01)


def test_observation_types_are_the_registry():
    from lrp_gym.config import OBSERVATION_TYPES, ObservationConfig
    from lrp_gym.envs import observations

    assert set(OBSERVATION_TYPES) == set(observations.OBSERVATION_TYPES)

    @observations.register_observation("custom-test")
    class Custom(observations.ObservationType):
        pass

    try:
        assert ObservationConfig(type="custom-test").type == "custom-test"
    finally:
        del observations.OBSERVATION_TYPES["custom-test"]
    with pytest.raises(ValueError, match="unknown observation type 'custom-test'"):
        ObservationConfig(type="custom-test")


def test_room_larger_than_indoor_is_rejected_before_any_grid_is_built():
    """A fuzzed room of 5e16 m once made the free-space check allocate exabytes."""
    from lrp_gym.config import ScenarioError, load_scenario

    with pytest.raises(ScenarioError, match="room.size"):
        load_scenario("ipin2023").with_overrides({"room": {"size": [5.0, 4.8e16, 4.0]}})
