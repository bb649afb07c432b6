"""The PPO config: rl-baselines3-zoo sections plus lrp-gym's own training settings.

``configs/ppo.yaml`` maps env ids to hyperparameters in the zoo's format (``n_envs``,
``n_timesteps``, ``policy``, ``normalize``, ``policy_kwargs`` as a Python-expression string,
``lin_<x>`` linear schedules, ``env_kwargs``), so ``python -m rl_zoo3.train -conf
configs/ppo.yaml`` reads it unchanged. Settings the zoo takes on its command line instead live
under the top-level key ``lrp-gym`` (the zoo reads only the section of the env it trains)::

    lrp-gym:
      LRPRadarNavFast-v0: {vec_env: batch, eval_freq: 20000, n_eval_episodes: 10,
                           checkpoint_freq: 10000, eval_env_id: LRPRadarNavFast-v0}

(zoo equivalents: ``--vec-env``, ``--eval-freq``, ``--eval-episodes``, ``--save-freq``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from lrp_gym.config import CONFIGS_DIR
from lrp_gym.errors import InputError

DEFAULT_CONFIG = CONFIGS_DIR / "ppo.yaml"
LRP_KEY = "lrp-gym"
EXTRA_KEYS = ("vec_env", "eval_env_id", "eval_freq", "n_eval_episodes", "checkpoint_freq")


def _read_yaml(path: Path) -> Any:
    if not path.is_file():
        raise InputError(f"config: no such file: {path}")
    try:
        return yaml.safe_load(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError as exc:
        raise InputError(f"config: {path} is not UTF-8 text: {exc.reason}") from None
    except OSError as exc:
        raise InputError(f"config: cannot read {path}: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        raise InputError(f"config: {path} is not valid YAML: {exc}") from None


def load_hyperparams(
    path: str | Path | None = None, env_id: str | None = None
) -> tuple[str, dict[str, Any]]:
    """The hyperparameters of ``env_id`` (default: the first zoo section) from a zoo-style YAML.

    The returned section holds the zoo keys plus the env's entries of the ``lrp-gym`` block.

    Raises
    ------
    InputError
        Missing, unreadable or non-UTF-8 file, invalid YAML, no section for ``env_id``, or a
        section that is not a mapping.
    """
    path = Path(path) if path is not None else DEFAULT_CONFIG
    data = _read_yaml(path)
    if not isinstance(data, dict) or not any(k != LRP_KEY for k in data):
        raise InputError(f"config: {path} must map env ids to hyperparameters")
    sections = [str(k) for k in data if k != LRP_KEY]
    env_id = env_id or sections[0]
    if env_id not in sections:
        raise InputError(
            f"env_id: {path} has no section {env_id!r}; sections: {', '.join(sections)}"
        )
    section, extras = data[env_id], (data.get(LRP_KEY) or {})
    if not isinstance(extras, dict):
        raise InputError(f"config: {LRP_KEY} in {path} must map env ids to settings")
    extra = extras.get(env_id) or {}
    for what, value in ((env_id, section), (f"{LRP_KEY}.{env_id}", extra)):
        if not isinstance(value, dict):
            raise InputError(
                f"config: section {what!r} of {path} must be a mapping, got {type(value).__name__}"
            )
    unknown = sorted(set(extra) - set(EXTRA_KEYS))
    if unknown:
        raise InputError(
            f"config: unknown {LRP_KEY}.{env_id} setting(s) {', '.join(unknown)} in {path}; "
            f"known: {', '.join(EXTRA_KEYS)}"
        )
    return str(env_id), {**section, **extra}


def _schedule(value: Any) -> Any:
    """Zoo's ``lin_<x>``: linear decay from x to 0 over training (else the value as is)."""
    if isinstance(value, str) and value.startswith("lin_"):
        start = float(value[4:])
        return lambda progress_remaining: progress_remaining * start
    return float(value) if isinstance(value, str) else value


def _eval_expr(text: str, what: str) -> Any:
    """Evaluate a zoo-style Python expression (``dict(net_arch=[64, 64], activation_fn=nn.Tanh)``)."""
    from torch import nn

    try:
        return eval(
            text, {"__builtins__": {}}, {"dict": dict, "nn": nn, "True": True, "False": False}
        )  # noqa: S307
    except Exception as exc:
        raise InputError(f"config: cannot parse {what} {text!r}: {exc}") from None


def split_hyperparams(hp: dict[str, Any]) -> dict[str, Any]:
    """Split a section into the parts the trainer needs (values converted).

    Returns
    -------
    dict
        ``n_envs``, ``n_timesteps``, ``policy``, ``normalize`` (kwargs for VecNormalize or
        None), ``env_kwargs``, the lrp-gym extras, and ``ppo`` (kwargs for PPO).
    """
    hp = dict(hp)
    try:
        n_envs = int(hp.pop("n_envs", 1))
        n_timesteps = int(float(hp.pop("n_timesteps", 1e5)))
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(f"config: n_envs / n_timesteps must be numbers: {exc}") from None
    if n_envs < 1:
        raise InputError(f"config: n_envs must be at least 1, got {n_envs}")
    out: dict[str, Any] = {
        "n_envs": n_envs,
        "n_timesteps": n_timesteps,
        "policy": hp.pop("policy", "MlpPolicy"),
        "env_kwargs": dict(hp.pop("env_kwargs", None) or {}),
    }
    norm = hp.pop("normalize", False)
    if isinstance(norm, str):
        norm = _eval_expr(norm, "normalize")
    out["normalize"] = (dict(norm) if isinstance(norm, dict) else {}) if norm else None
    for key in EXTRA_KEYS:
        out[key] = hp.pop(key, None)
    for key in ("learning_rate", "clip_range"):
        if key in hp:
            hp[key] = _schedule(hp[key])
    if isinstance(hp.get("policy_kwargs"), str):
        hp["policy_kwargs"] = _eval_expr(hp["policy_kwargs"], "policy_kwargs")
    out["ppo"] = hp
    return out


def schedules(ppo_kwargs: dict[str, Any]) -> dict[str, Any]:
    """``learning_rate`` and ``clip_range`` to continue training with (PPO's defaults if unset)."""
    import inspect

    from stable_baselines3 import PPO

    params = inspect.signature(PPO.__init__).parameters
    return {k: ppo_kwargs.get(k, params[k].default) for k in ("learning_rate", "clip_range")}
