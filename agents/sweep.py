"""``lrp-gym sweep``: Ray Tune over ``lrp-gym train`` trials (seeds x a hyperparameter grid).

A sweep file (YAML) names the PPO config and env section to start from and what to vary::

    config: ppo.yaml            # zoo-style PPO config (beside this file, or a shipped one)
    env: LRPRadarNavFast-v0     # its section (default: the first)
    timesteps: 256              # per trial
    report_every: 128           # env steps between Tune reports (an evaluation each)
    seeds: [0, 1]
    grid: {learning_rate: [3.0e-4, 1.0e-3]}   # every combination, for every seed
    hyperparams: {n_envs: 1, n_steps: 64}     # fixed changes to the section, every trial
    lrp-gym: {vec_env: dummy, n_eval_episodes: 2}   # the section's lrp-gym settings
    metric: success_rate        # or mean_reward: what picks the best trial
    max_failures: 1             # restarts of a lost trial, from its last checkpoint

Each trial is a :func:`agents.ppo.train` run in its own folder, trained in segments of
``report_every`` steps; after each segment it reports the evaluation (``success_rate``,
``mean_reward``, ``timesteps``) to Tune with the run folder as the checkpoint. A trial whose
worker is lost restarts from that checkpoint and resumes training from the run's newest
checkpoint, so it reaches the same step count; ``Tuner.restore`` completes a sweep whose
driver stopped.
"""

from __future__ import annotations

import itertools
import os
import shutil
from pathlib import Path
from typing import Any

import yaml

from agents.ppo_config import DEFAULT_CONFIG, EXTRA_KEYS, LRP_KEY, load_hyperparams
from lrp_gym.config import CONFIGS_DIR
from lrp_gym.errors import InputError

KEYS: tuple[str, ...] = ("config", "env", "timesteps", "report_every", "seeds", "grid")
KEYS += ("hyperparams", LRP_KEY, "metric", "max_failures")
METRICS = ("success_rate", "mean_reward")
#: Fault injection for tests: one trial of seed 0 kills its worker process once, after its
#: first report (it creates the marker file this variable names).
FAIL_ONCE_ENV = "LRP_GYM_SWEEP_FAIL_ONCE"


def _bad(path: Path, text: str) -> InputError:
    return InputError(f"CONFIG: {path}: {text}")


def _positive(doc: dict, key: str, path: Path, default: int | None = None) -> int:
    value = doc.get(key, default)
    if not isinstance(value, int) or isinstance(value, bool) or value < 1:
        raise _bad(path, f"{key}: expected a whole number >= 1, got {value!r}")
    return value


def load_sweep(path: str | Path) -> dict[str, Any]:
    """The sweep file, checked and completed (every problem names its key).

    Raises
    ------
    InputError
        Missing or unreadable file, unknown keys, bad values, or a PPO config / env section
        that :func:`agents.ppo_config.load_hyperparams` rejects.
    """
    path = Path(path)
    if not path.is_file():
        raise _bad(path, "no such file")
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise _bad(path, f"not a readable YAML file ({exc})") from None
    if not isinstance(doc, dict):
        raise _bad(path, "expected a mapping of sweep settings")
    unknown = sorted(set(doc) - set(KEYS))
    if unknown:
        raise _bad(path, f"unknown key(s) {', '.join(unknown)}; known: {', '.join(KEYS)}")
    timesteps = _positive(doc, "timesteps", path)
    seeds = doc.get("seeds", [0])
    if not (isinstance(seeds, list) and seeds and all(isinstance(s, int) for s in seeds)):
        raise _bad(path, f"seeds: expected a list of whole numbers, got {seeds!r}")
    grid = doc.get("grid") or {}
    if not isinstance(grid, dict) or not all(isinstance(v, list) and v for v in grid.values()):
        raise _bad(path, "grid: expected a mapping of hyperparameter -> list of values")
    for key in ("hyperparams", LRP_KEY):
        if not isinstance(doc.get(key) or {}, dict):
            raise _bad(path, f"{key}: expected a mapping")
    extra = sorted(set(doc.get(LRP_KEY) or {}) - set(EXTRA_KEYS))
    if extra:
        raise _bad(path, f"{LRP_KEY}: unknown setting(s) {', '.join(extra)}")
    metric = doc.get("metric", "success_rate")
    if metric not in METRICS:
        raise _bad(path, f"metric: expected one of {', '.join(METRICS)}, got {metric!r}")
    config = _config_path(path, doc.get("config"))
    env_id, section = load_hyperparams(config, doc.get("env"))
    return {
        "file": str(path),
        "config": str(config),
        "env": env_id,
        "section": section,
        "timesteps": timesteps,
        "report_every": min(_positive(doc, "report_every", path, timesteps), timesteps),
        "seeds": seeds,
        "grid": grid,
        "hyperparams": dict(doc.get("hyperparams") or {}),
        LRP_KEY: dict(doc.get(LRP_KEY) or {}),
        "metric": metric,
        "max_failures": _positive(doc, "max_failures", path, 1) if "max_failures" in doc else 1,
    }


def _config_path(sweep_file: Path, name: str | None) -> Path:
    """The PPO config: the shipped one by default; a relative name beside the sweep file,
    else among the shipped configs."""
    if name is None:
        return DEFAULT_CONFIG
    p = Path(name)
    if p.is_absolute():
        return p
    beside = sweep_file.parent / p
    return beside if beside.is_file() else CONFIGS_DIR / p


def trials(sweep: dict[str, Any]) -> list[dict[str, Any]]:
    """Every trial's parameters: each seed with each combination of the grid."""
    names = sorted(sweep["grid"])
    combos = itertools.product(*(sweep["grid"][n] for n in names))
    return [
        {"seed": seed, **dict(zip(names, values))} for values in combos for seed in sweep["seeds"]
    ]


def write_trial_config(sweep: dict[str, Any], params: dict[str, Any], path: Path) -> Path:
    """The zoo-style config of one trial: the env's section with the sweep's fixed changes
    and the trial's grid values; its lrp-gym settings in the ``lrp-gym`` block."""
    section = {**sweep["section"], **sweep["hyperparams"]}
    section.update({k: v for k, v in params.items() if k != "seed"})
    extras = {k: section.pop(k) for k in EXTRA_KEYS if k in section}
    extras.update(sweep[LRP_KEY])
    doc = {sweep["env"]: section, LRP_KEY: {sweep["env"]: extras}}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return path


def run_trial(params: dict[str, Any], sweep: dict[str, Any]) -> None:
    """One Tune trial (a function trainable): train in segments, report after each."""
    from ray import tune

    from agents.checkpoints import list_checkpoints
    from agents.ppo import train

    run_dir = Path(tune.get_context().get_trial_dir()) / "run"
    restored = tune.get_checkpoint()
    restored_at = 0
    if restored is not None:  # a lost trial: continue from its last reported run folder
        with restored.as_directory() as saved:
            shutil.rmtree(run_dir, ignore_errors=True)
            shutil.copytree(saved, run_dir)
        restored_at = max((n for n, _ in list_checkpoints(run_dir)), default=0)
    config = write_trial_config(sweep, params, run_dir.parent / "trial.yaml")
    total, every = sweep["timesteps"], sweep["report_every"]
    for target in range(every, total + every, every):
        target = min(target, total)
        done = list_checkpoints(run_dir)
        if done and done[0][0] >= target:
            continue  # reached before the trial was lost
        info = train(
            config,
            sweep["env"],
            target,
            run_dir,
            resume=bool(done),
            seed=int(params["seed"]),
            progress_bar=False,
            log=lambda _msg: None,
        )
        last = info.get("last_eval") or {}
        metrics = {
            "timesteps": info["timesteps"],
            "success_rate": last.get("success_rate", 0.0),
            "mean_reward": last.get("mean_reward", float("-inf")),
            "restored_at": restored_at,  # steps of the checkpoint a lost trial resumed from
        }
        tune.report(metrics, checkpoint=tune.Checkpoint.from_directory(str(run_dir)))
        _maybe_fail_once(params)


def _maybe_fail_once(params: dict[str, Any]) -> None:
    marker = os.environ.get(FAIL_ONCE_ENV)
    if not marker or params["seed"] != 0:
        return
    try:
        os.close(os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY))  # one trial wins
    except FileExistsError:
        return
    os._exit(1)  # the worker process dies, as on a lost node: Tune restarts the trial


def run_sweep(
    sweep: dict[str, Any], out: Path, address: str, resume: bool = False
) -> dict[str, Any]:
    """Run (or, with ``resume``, complete) the sweep on Ray; the trials and the best one.

    Tune keeps its state in ``out/tune`` (one folder per trial, each with its run folder and
    its last checkpoint); ``resume`` restores it, rerunning unfinished and failed trials from
    their checkpoints.
    """
    import contextlib
    import sys

    from ray import tune

    from lrp_gym.experiments.cluster import connect

    os.environ.setdefault("TUNE_WARN_EXCESSIVE_EXPERIMENT_CHECKPOINT_SYNC_THRESHOLD_S", "0")
    connect(address)
    path = (out / "tune").resolve()
    trainable = tune.with_resources(tune.with_parameters(run_trial, sweep=sweep), {"cpu": 1})
    metric = sweep["metric"]
    with contextlib.redirect_stdout(sys.stderr):  # Tune's tables: never on stdout
        if resume and tune.Tuner.can_restore(str(path)):
            tuner = tune.Tuner.restore(str(path), trainable, resume_errored=True)
        else:
            space = {"seed": tune.grid_search(sweep["seeds"])}
            space |= {k: tune.grid_search(v) for k, v in sweep["grid"].items()}
            tuner = tune.Tuner(
                trainable,
                param_space=space,
                tune_config=tune.TuneConfig(metric=metric, mode="max"),
                run_config=tune.RunConfig(
                    name=path.name,
                    storage_path=str(path.parent),
                    failure_config=tune.FailureConfig(max_failures=sweep["max_failures"]),
                    checkpoint_config=tune.CheckpointConfig(num_to_keep=1),
                    verbose=0,
                ),
            )
        grid = tuner.fit()
    results = [grid[i] for i in range(len(grid))]
    rows = [_trial_row(r) for r in results]
    ok = [r for r in results if r.error is None and r.metrics]
    if not ok:
        raise RuntimeError(f"every trial failed; see the trial folders in {path}")
    other = "mean_reward" if metric == "success_rate" else "success_rate"
    best = max(ok, key=lambda r: _rank(r.metrics or {}, metric, other))  # ties: the other
    row = _trial_row(best) | {
        "checkpoint": None if best.checkpoint is None else best.checkpoint.path
    }
    return {"tune_dir": str(path), "metric": metric, "trials": rows, "best": row}


def _rank(metrics: dict[str, Any], metric: str, other: str) -> tuple[float, float]:
    """What orders trials: the metric, then the other one."""
    return float(metrics[metric]), float(metrics[other])


def _trial_row(r: Any) -> dict[str, Any]:
    """One trial: its parameters, its last report, where it is, and an error if it failed."""
    m = r.metrics or {}
    return {
        "params": dict(r.config),
        "timesteps": m.get("timesteps"),
        "success_rate": m.get("success_rate"),
        "mean_reward": m.get("mean_reward"),
        "restored_at": m.get("restored_at"),
        "path": r.path,
        "error": None if r.error is None else str(r.error).splitlines()[0][:200],
    }
