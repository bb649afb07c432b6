"""Every generated scenario validates and runs the whole chain without an exception.

``random_scenario`` covers rooms, obstacles, reflector catalogues (with unused types),
waveforms and paths; each draw goes through reproduce-paper's machinery, every env variant and
one pure-pursuit episode, with observations finite and inside the observation space. With
``random_perturbations`` on top, draws also run through the vector env (both fidelities, both
task modes, several robots, autoresets).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import lrp_gym  # noqa: F401  (registers the env ids)
from agents.registry import make_agent
from lrp_gym.config import ScenarioConfig
from lrp_gym.config.perturbations import PerturbationsConfig
from lrp_gym.envs import ENV_VARIANTS
from lrp_gym.experiments.episodes import run_episode
from lrp_gym.experiments.reproduce import reproduce
from lrp_gym.experiments.scenarios import random_perturbations, random_scenario

SEEDS = st.integers(0, 2**32 - 1)


def _finite_in_space(space: gym.Space, obs) -> bool:
    leaves = obs.values() if isinstance(obs, dict) else [obs]
    return space.contains(obs) and all(np.all(np.isfinite(v)) for v in leaves)


def run_chain(cfg: ScenarioConfig, seed: int, *, steps: int = 2, episode_env: str = "") -> None:
    """reproduce-paper for one run, ``steps`` random steps per env variant, one episode."""
    assert ScenarioConfig.from_dict(cfg.to_dict()) == cfg  # validates as written to YAML
    result = reproduce(cfg, runs=1, seed=seed, estimator="cluster")
    assert np.all(np.isfinite(result.amcl_errors_m)) and np.all(np.isfinite(result.lut_errors_m))
    rng = np.random.default_rng(seed)
    for env_id in ENV_VARIANTS:
        env = gym.make(env_id, scenario=cfg, max_episode_steps=40)
        obs, _ = env.reset(seed=seed)
        assert _finite_in_space(env.observation_space, obs)
        for _ in range(steps):
            action = rng.uniform(-1.0, 1.0, 2).astype(np.float32)
            obs, reward, *_ = env.step(action)
            assert _finite_in_space(env.observation_space, obs) and np.isfinite(reward)
        if env_id == episode_env or not episode_env:
            res = run_episode(env, make_agent("pure-pursuit", env), seed)
            assert res.steps >= 1 and np.all(np.isfinite(res.loc_error_m))
        env.close()


def random_localization(rng: np.random.Generator) -> dict:
    """Localiser settings a user may pick: method, what it weighs, its start, the clutter map."""
    loc = {
        "method": str(rng.choice(["amcl", "amcl", "lut", "grid"])),
        "measurements": str(rng.choice(["detections", "tracks"])),
        "recovery_measurements": str(rng.choice(["detections", "tracks"])),
        "init": str(rng.choice(["uniform", "uniform", "gaussian"])),
        "estimator": str(rng.choice(["cluster", "best_k"])),
        "slip_adaptive": bool(rng.random() < 0.3),
        "clutter_map": {"enabled": bool(rng.random() < 0.3)},
    }
    if loc["method"] == "grid":  # coarse cells: a 12 m room at the default 5 cm is slow
        loc.update(grid_cell_m=0.15, grid_cell_deg=15.0)
    return loc


def run_perturbed_batch(seed: int, *, small: bool, steps: int) -> None:
    """A random scenario with random perturbations, radar fidelity, task mode, localiser,
    observation and batch size, through the vector env for ``steps`` random steps (episodes of at most 40 steps)."""
    rng = np.random.default_rng(seed)
    data = random_scenario(rng, small=small).to_dict()
    data["perturbations"] = random_perturbations(rng)
    data["radar"]["fidelity"] = str(rng.choice(["signal", "detections"]))
    data["task"].update(mode=str(rng.choice(["goal", "path"])), max_episode_steps=40)
    data["localization"] = {**data.get("localization", {}), **random_localization(rng)}
    data["env"] = {"observation": {"type": str(rng.choice(["estimated", "oracle"]))}}
    cfg = ScenarioConfig.from_dict(data, f"perturbed draw {seed}")
    n = int(rng.integers(1, 4))
    venv = gym.make_vec("LRPRadarNav-v0", num_envs=n, scenario=cfg)
    obs, _ = venv.reset(seed=seed)
    for _ in range(steps):
        obs, rewards, *_ = venv.step(rng.uniform(-1.0, 1.0, (n, 2)).astype(np.float32))
        assert _finite_in_space(venv.observation_space, obs) and np.all(np.isfinite(rewards))
    venv.close()


def test_perturbation_draws_cover_every_kind_and_validate():
    draws = [random_perturbations(np.random.default_rng(s)) for s in range(30)]
    assert set().union(*draws) == set(PerturbationsConfig.model_fields)
    assert {} in draws and max(map(len, draws)) >= 4
    for d in draws:
        assert set(PerturbationsConfig.model_validate(d).active()) == set(d)


@settings(
    max_examples=2, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(seed=SEEDS)
def test_a_small_perturbed_draw_runs_through_the_vector_env(seed):
    run_perturbed_batch(seed, small=True, steps=12)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(40))
def test_perturbed_scenarios_sweep(seed):
    # Long enough for the reflector monitor to name suspects one after another (it crashed
    # on a second suspect in a surveyed room) and for several autoresets.
    run_perturbed_batch(seed, small=False, steps=150)


def test_generator_is_seeded_and_covers_the_space():
    a = random_scenario(np.random.default_rng(7))
    assert a == random_scenario(np.random.default_rng(7))
    cfgs = [random_scenario(np.random.default_rng(s)) for s in range(40)]
    sizes = np.array([c.room.size[:2] for c in cfgs])
    assert sizes.min() >= 3.0 and sizes.max() <= 12.0 and np.ptp(sizes) > 6.0
    assert {len(c.room.obstacles) for c in cfgs} == {0, 1, 2, 3}
    kinds = {t.kind for c in cfgs for t in c.reflectors.types.values()}
    assert kinds == {"trihedral", "sphere", "luneburg", "van_atta", "point"}
    assert {len(c.reflectors.layout) for c in cfgs} <= set(range(3, 9))
    unused = [c for c in cfgs if set(c.reflectors.types) - {r.type for r in c.reflectors.layout}]
    assert unused  # catalogue types without a reflector are drawn too
    assert all(5 <= len(c.task.path) <= 30 for c in cfgs)
    bw = np.array([c.radar.bandwidth_hz for c in cfgs])
    assert bw.min() >= 0.5e9 and bw.max() <= 4e9


@settings(
    max_examples=3,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(seed=SEEDS)
def test_every_small_generated_scenario_runs_the_whole_chain(seed):
    cfg = random_scenario(np.random.default_rng(seed), small=True)
    run_chain(cfg, seed, episode_env="LRPRadarNavFast-v0")


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(40))
def test_generated_scenarios_sweep(seed):
    run_chain(random_scenario(np.random.default_rng(seed)), seed, steps=3)


def test_room_sweep_records_both_fingerprint_kinds():
    from lrp_gym.experiments.rooms import summary, sweep

    seen = []
    results = sweep([4], small=True, progress=seen.append)
    assert seen == results and results[0].seed == 4
    r = results[0]
    cfg = random_scenario(np.random.default_rng(4), small=True)
    assert r.size_m == tuple(round(v, 2) for v in cfg.room.size) and r.frames >= 2
    assert np.isfinite(r.amcl_radar_m) and np.isfinite(r.amcl_true_m)
    assert summary(results)["median_amcl_true_m"] == r.amcl_true_m


def test_room_sweep_runs_the_grid_filter_when_asked():
    from lrp_gym.experiments.rooms import summary, sweep

    (r,) = sweep([4], small=True, localizer="grid")
    assert r.grid_radar_m is not None and np.isfinite(r.grid_radar_m)
    s = summary([r])
    assert s["share_grid_radar_within_0_15_m"] == float(r.grid_radar_m <= 0.15)
    lost = r.grid_radar_m <= 0.15 and not r.amcl_radar_m <= 0.15
    assert s["rooms_grid_localises_amcl_does_not"] == ([4] if lost else [])
    assert "share_grid_radar_within_0_15_m" not in summary(sweep([4], small=True))


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--random-rooms", "-1"], "--random-rooms"),
        (["--random-rooms", "2", "--plot", "x.png"], "--plot"),
    ],
)
def test_random_rooms_option_is_checked(args, message, capsys):
    from lrp_gym.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["reproduce-paper", *args])
    assert exc.value.code == 2 and message in capsys.readouterr().err


def test_random_rooms_json_is_json_on_stdout(monkeypatch, capsys):
    import json

    from lrp_gym.cli import main
    from lrp_gym.experiments import rooms

    full = rooms.sweep
    monkeypatch.setattr(rooms, "sweep", lambda *a, **k: full(*a, **{**k, "small": True}))
    with pytest.raises(SystemExit) as exc:
        main(["reproduce-paper", "--random-rooms", "1", "--runs", "1", "--json"])
    assert exc.value.code == 0
    data = json.loads(capsys.readouterr().out)
    assert data["rooms"] == 1
    r = data["per_room"][0]
    assert data["share_amcl_radar_within_0_15_m"] == float(r["amcl_radar_m"] <= 0.15)
