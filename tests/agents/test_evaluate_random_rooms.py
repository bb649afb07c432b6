"""``lrp-gym evaluate --random-rooms N``: closed-loop episodes on generated rooms.

The invariant that makes the per-room numbers trustworthy: a room of ``--random-rooms`` is
exactly the scenario ``random_scenario(default_rng(room_seed))`` evaluated alone (written to
YAML and run with ``lrp-gym evaluate ROOM.yaml``, the same options and episode seeds).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from agents.registry import make_agent
from lrp_gym.cli import main
from lrp_gym.config import save_scenario
from lrp_gym.experiments import room_episodes as rooms
from lrp_gym.experiments.episodes import EpisodeResult
from lrp_gym.experiments.scenarios import random_scenario

GOAL_FAST = {"radar": {"fidelity": "detections"}, "task": {"mode": "goal"}}
#: The per-room keys that ``lrp-gym evaluate --json`` of one scenario reports too.
SHARED_KEYS = (
    "success_rate",
    "collision_rate",
    "time_localised",
    "converged_share",
    "confidently_wrong_rate",
    "stuck_wrong_rate",
)


def run_cli(capsys, *args: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exc:
        main(list(args))
    out, err = capsys.readouterr()
    return int(exc.value.code or 0), out, err


def pure_pursuit(env):
    return make_agent("pure-pursuit", env)


def test_small_rooms_run_the_same_episode_seeds_in_each_room():
    got = []
    res = rooms.run_rooms(
        [3, 1], pure_pursuit, episodes=1, seed=7000, overrides=GOAL_FAST, small=True,
        progress=got.append,
    )  # fmt: skip
    assert [r.seed for r in res] == [3, 1] and got == res  # progress as each room finishes
    for r in res:
        cfg = random_scenario(np.random.default_rng(r.seed), small=True)
        assert r.size_m == tuple(cfg.room.size) and r.reflectors == len(cfg.reflectors.layout)
        assert r.obstacles == len(cfg.room.obstacles)
        kinds = {cfg.reflectors.types[x.type].kind for x in cfg.reflectors.layout}
        assert r.kinds.split("+") == sorted(kinds)
        assert (r.task, r.fidelity, r.env_id) == ("goal", "detections", "LRPRadarNav-v0")
        assert [e.seed for e in r.episodes] == [7000] and r.episodes[0].steps > 0
    data = rooms.summary(res)
    assert data["rooms"] == 2 and data["pooled"]["episodes"] == 2
    assert [row["seed"] for row in data["per_room"]] == [3, 1]
    # pooled = summed over rooms (computed from the episodes, not from the rows)
    conv = sum(row["converged_steps"] for row in data["per_room"])
    wrong = sum(row["wrong_converged_steps"] for row in data["per_room"])
    assert (data["converged_steps"], data["wrong_converged_steps"]) == (conv, wrong)
    assert conv > 0 and data["pooled"]["confidently_wrong_rate"] == pytest.approx(wrong / conv)
    json.dumps(data, allow_nan=False)  # strict JSON: None, never NaN


def _episode(errors_m, converged) -> EpisodeResult:
    err = np.asarray(errors_m, float)
    n = len(err)
    z = np.zeros((n + 1, 2))
    return EpisodeResult(
        0, True, False, n, 1.0, 1.0, 1.0, err, np.asarray(converged, bool), np.zeros(n), z, z,
        np.zeros((2, 2)),
    )  # fmt: skip


def _room(seed: int, *episodes: EpisodeResult) -> rooms.RoomEpisodes:
    return rooms.RoomEpisodes(
        seed, (4.0, 4.0, 3.0), 0, 3, "sphere", "LRPRadarNav-v0", "goal", "detections", episodes
    )


def test_pooled_rate_weighs_rooms_by_their_converged_steps():
    # room 0: 1 of 2 converged steps wrong; room 1: 0 of 8 (plus an unconverged wrong step);
    # room 2: never converged. Pooled 1/10, not the mean of the rates (0.25).
    many = _episode([0.1] * 8 + [2.0], [True] * 8 + [False])
    data = rooms.summary(
        [
            _room(0, _episode([0.5, 0.1, 0.9], [True, True, False])),
            _room(1, many),
            _room(2, _episode([3.0, 3.0], [False, False])),
        ]
    )
    rows = data["per_room"]
    assert [r["confidently_wrong_rate"] for r in rows] == [0.5, 0.0, None]
    assert [(r["wrong_converged_steps"], r["converged_steps"]) for r in rows] == [
        (1, 2), (0, 8), (0, 0),
    ]  # fmt: skip
    assert data["pooled"]["confidently_wrong_rate"] == pytest.approx(1 / 10)
    assert (data["wrong_converged_steps"], data["converged_steps"]) == (1, 10)
    assert data["rooms_confidently_wrong_over_1pct"] == 1  # the unconverged room is not wrong
    assert data["pooled"]["episodes"] == 3 and "per_episode" not in data["pooled"]
    json.dumps(data, allow_nan=False)


def test_a_room_equals_its_scenario_evaluated_alone(capsys, tmp_path):
    """The hand loop (room to YAML, ``lrp-gym evaluate ROOM.yaml``) gives the same numbers,
    episode by episode; --out writes what --json prints and --plot draws the pooled steps."""
    opts = ["--task", "goal", "--fidelity", "detections", "--episodes", "1", "--seed", "7000"]
    out_path, png = tmp_path / "rooms.json", tmp_path / "rel.png"
    code, out, err = run_cli(
        capsys, "evaluate", "--random-rooms", "2", *opts, "--json", "--out", str(out_path),
        "--plot", str(png),
    )  # fmt: skip
    assert code == 0, err
    doc = json.loads(out)
    assert doc == json.loads(out_path.read_text()) and png.stat().st_size > 10_000
    assert [line.split(":")[0] for line in err.splitlines() if line.startswith("room")] == [
        "room 0", "room 1",
    ]  # fmt: skip
    assert doc["rooms"] == 2 and doc["task"] == "goal" and doc["fidelity"] == "detections"
    room_yaml = tmp_path / "room1.yaml"
    save_scenario(random_scenario(np.random.default_rng(1)), room_yaml)
    code, out, _ = run_cli(capsys, "evaluate", str(room_yaml), *opts, "--json")
    assert code == 0
    alone, row = json.loads(out), doc["per_room"][1]
    assert alone["per_episode"][0]["steps"] > 0
    assert {k: row[k] for k in SHARED_KEYS} == {k: alone[k] for k in SHARED_KEYS}
    # one room, one episode: the pooled numbers over room 1 alone are the scenario's
    again = rooms.run_rooms([1], pure_pursuit, episodes=1, seed=7000, overrides=GOAL_FAST)
    pooled = rooms.summary(again)["pooled"]
    assert pooled["mean_loc_error_m"] == alone["mean_loc_error_m"]
    assert pooled["mean_path_length_m"] == alone["mean_path_length_m"]
    assert [e.row() for e in again[0].episodes] == alone["per_episode"]


@pytest.mark.parametrize(
    "args, flag",
    [
        (["--random-rooms", "-1"], "--random-rooms"),
        (["--random-rooms", "2", "--gif", "{tmp}/e.gif"], "--gif"),
        (["--random-rooms", "2", "--ray", "auto"], "--ray"),
    ],
)
def test_bad_random_rooms_input_exits_2_naming_the_flag(capsys, tmp_path, args, flag):
    argv = ["evaluate", *(a.format(tmp=tmp_path) for a in args), "--episodes", "1"]
    code, out, err = run_cli(capsys, *argv)
    assert code == 2 and out == ""
    assert err.startswith(f"error: {flag}:") and len(err.strip().splitlines()) == 1
    assert "Traceback" not in err and list(tmp_path.iterdir()) == []
