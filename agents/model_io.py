"""Model files that do not run code: PPO zips loaded without unpickling, statistics as JSON.

An SB3 model zip stores its weights as ``*.pth`` (read with ``torch.load(weights_only=True)``)
and its settings in a JSON ``data`` entry in which some values (policy class, spaces,
schedules, buffers) are cloudpickled. :func:`load_ppo_safely` reads ``data`` as plain JSON and
hands SB3 a replacement for *every* pickled value (``custom_objects``), so SB3 never unpickles
anything; a pickled value it cannot replace from a short allow-list is refused.

VecNormalize statistics are written as plain JSON beside every model (``vecnormalize.json``,
or ``rl_model_vecnormalize_<n>_steps.json`` beside a checkpoint) instead of SB3's pickle.
``python -m agents.model_io FILE.pkl`` converts an old (trusted!) pickle once.
"""

from __future__ import annotations

import json
import re
import sys
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from lrp_gym.errors import InputError

STATS_FORMAT = "lrp-gym.vecnormalize/1"
# Runtime state SB3 pickles but rebuilds itself when it is None.
_RUNTIME_FIELDS = (
    "_last_obs",
    "_last_episode_starts",
    "_last_original_obs",
    "ep_info_buffer",
    "ep_success_buffer",
)
_SCHEDULE_FIELDS = ("learning_rate", "lr_schedule", "clip_range", "clip_range_vf")
_ACTIVATIONS = ("Tanh", "ReLU", "ELU", "LeakyReLU", "GELU", "SiLU", "Sigmoid", "Softplus")
_OPTIMIZERS = ("Adam", "AdamW", "SGD", "RMSprop")
_CLASS_REPR = re.compile(r"^<class '([\w.]+)'>$")


# --------------------------------------------------------------------------- statistics
def stats_path_for(model_path: str | Path) -> Path:
    """Where the statistics of a model are written (checkpoint naming kept from SB3)."""
    p = Path(model_path)
    m = re.fullmatch(r"(.+)_(\d+)_steps", p.stem)
    if m:
        return p.with_name(f"{m.group(1)}_vecnormalize_{m.group(2)}_steps.json")
    return p.with_name("vecnormalize.json")


def find_stats(model_path: str | Path, suffix: str = ".json") -> Path | None:
    """The statistics saved with a model, if any.

    Looks for, in order: ``<stem>_vecnormalize<suffix>``; for a checkpoint
    ``<prefix>_<n>_steps.zip`` the file ``<prefix>_vecnormalize_<n>_steps<suffix>``; and
    ``vecnormalize<suffix>`` in the model's folder.
    """
    p = Path(model_path)
    candidates = [p.with_name(f"{p.stem}_vecnormalize{suffix}")]
    m = re.fullmatch(r"(.+)_(\d+)_steps", p.stem)
    if m:
        candidates.append(p.with_name(f"{m.group(1)}_vecnormalize_{m.group(2)}_steps{suffix}"))
    candidates.append(p.with_name(f"vecnormalize{suffix}"))
    return next((c for c in candidates if c.is_file()), None)


def stats_to_dict(vn: Any) -> dict[str, Any]:
    """A VecNormalize's settings and running statistics as plain JSON (``None``: no VecNormalize)."""
    if vn is None:
        return {"format": STATS_FORMAT, "norm_obs": False, "norm_reward": False}
    if isinstance(vn.obs_rms, dict):
        raise InputError("normalisation statistics of Dict observations are not supported")

    def rms(r: Any) -> dict[str, Any]:
        return {
            "mean": np.asarray(r.mean, dtype=float).tolist(),
            "var": np.asarray(r.var, dtype=float).tolist(),
            "count": float(r.count),
        }

    return {
        "format": STATS_FORMAT,
        "norm_obs": bool(vn.norm_obs),
        "norm_reward": bool(vn.norm_reward),
        "clip_obs": float(vn.clip_obs),
        "clip_reward": float(vn.clip_reward),
        "gamma": float(vn.gamma),
        "epsilon": float(vn.epsilon),
        "obs_rms": rms(vn.obs_rms),
        "ret_rms": rms(vn.ret_rms),
    }


def write_stats(vn: Any, path: str | Path) -> Path:
    """Write :func:`stats_to_dict` atomically (floats round-trip exactly through JSON)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(stats_to_dict(vn), indent=1) + "\n", encoding="utf-8")
    tmp.replace(path)
    return path


def read_stats(path: str | Path, option: str = "model_path") -> dict[str, Any]:
    """Read and check a statistics JSON; :class:`InputError` naming ``option`` if it is bad."""
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
        if doc.get("format") != STATS_FORMAT:
            raise ValueError(f"format is {doc.get('format')!r}, expected {STATS_FORMAT!r}")
        for key in ("obs_rms", "ret_rms") if doc["norm_obs"] or doc["norm_reward"] else ():
            for part in ("mean", "var", "count"):
                doc[key][part]  # noqa: B018  (fails early on a truncated file)
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise InputError(f"{option}: cannot read normalisation statistics {path}: {exc}") from None
    return doc


def _rms(d: dict[str, Any]) -> Any:
    from stable_baselines3.common.running_mean_std import RunningMeanStd

    r = RunningMeanStd(shape=np.shape(d["mean"]))
    r.mean = np.asarray(d["mean"], dtype=np.float64)
    r.var = np.asarray(d["var"], dtype=np.float64)
    r.count = float(d["count"])
    return r


class ObsNormalizer:
    """Frozen observation normalisation, computed exactly as VecNormalize does."""

    training = False

    def __init__(self, doc: dict[str, Any]) -> None:
        self.obs_rms = _rms(doc["obs_rms"])
        self.clip_obs = float(doc["clip_obs"])
        self.epsilon = float(doc["epsilon"])

    def normalize_obs(self, obs: np.ndarray) -> np.ndarray:
        """``clip((obs - mean) / sqrt(var + eps), -clip_obs, clip_obs)`` as float32."""
        r = self.obs_rms
        out = np.clip((obs - r.mean) / np.sqrt(r.var + self.epsilon), -self.clip_obs, self.clip_obs)
        return out.astype(np.float32)


def obs_normalizer(doc: dict[str, Any]) -> ObsNormalizer | None:
    """The frozen observation normaliser of a statistics document (None: not normalised)."""
    return ObsNormalizer(doc) if doc["norm_obs"] else None


def vecnormalize_from_stats(doc: dict[str, Any], venv: Any) -> Any:
    """A training VecNormalize around ``venv`` carrying the saved statistics (for --resume)."""
    from stable_baselines3.common.vec_env import VecNormalize

    keys = ("norm_obs", "norm_reward", "clip_obs", "clip_reward", "gamma", "epsilon")
    vn = VecNormalize(venv, training=True, **{k: doc[k] for k in keys})
    vn.obs_rms, vn.ret_rms = _rms(doc["obs_rms"]), _rms(doc["ret_rms"])
    return vn


def save_model(model: Any, zip_path: str | Path) -> list[Path]:
    """Save a model and its statistics JSON, each atomically; returns the files written.

    The statistics go first, so a model zip never exists without them.
    """
    zip_path = Path(zip_path)
    stats = write_stats(model.get_vec_normalize_env(), stats_path_for(zip_path))
    tmp = zip_path.with_name(zip_path.stem + ".tmp.zip")
    model.save(tmp)
    tmp.replace(zip_path)
    return [zip_path, stats]


# --------------------------------------------------------------------------- model zip
def read_zip_data(path: Path, option: str = "model_path") -> dict[str, Any]:
    """The ``data`` entry of an SB3 zip as plain JSON (nothing is unpickled)."""
    try:
        with zipfile.ZipFile(path) as z:
            return json.loads(z.read("data"))
    except (OSError, KeyError, ValueError, zipfile.BadZipFile) as exc:
        raise InputError(
            f"{option}: {path} is not a readable PPO model (no SB3 zip): {exc}"
        ) from None


def _box(field: dict[str, Any]) -> Any:
    """A Box rebuilt from the printed ``low``/``high`` of a pickled space (None if not a Box)."""
    import gymnasium as gym

    if "gymnasium.spaces.box.Box" not in str(field.get(":type:")):
        return None
    shape, dtype = tuple(field["_shape"]), np.dtype(field["dtype"])
    bounds = []
    for key in ("low", "high"):
        text = str(field[key])
        if "..." in text:  # numpy abbreviates large arrays: bounds unknown
            return None
        values = np.array(text.replace("[", " ").replace("]", " ").split(), dtype=float)
        bounds.append(values.reshape(shape).astype(dtype))
    return gym.spaces.Box(bounds[0], bounds[1], shape, dtype)


def _same_box(a: Any, b: Any) -> bool:
    return (
        a.shape == b.shape
        and a.dtype == b.dtype
        and np.allclose(a.low, b.low, rtol=1e-5, atol=1e-5)
        and np.allclose(a.high, b.high, rtol=1e-5, atol=1e-5)
    )


def _space(data: dict, key: str, given: Any, path: Path, option: str) -> Any:
    """The space to load the model with: ``given`` (the env's) after checking it matches."""
    field = data.get(key)
    if not (isinstance(field, dict) and ":serialized:" in field):
        raise InputError(f"{option}: {path} has no readable {key}")
    what = key.replace("_space", "")
    shape = tuple(field.get("_shape") or ())
    if given is not None and shape != tuple(given.shape):
        raise InputError(
            f"{option}: {path} was trained for {what}s of shape {shape}, "
            f"the env has {tuple(given.shape)}"
        )
    try:
        saved = _box(field)
    except (KeyError, TypeError, ValueError):  # unreadable bounds
        saved = None
    if given is None:
        if saved is None:
            raise InputError(f"{option}: {path}: the {key} is not a readable Box")
        return saved
    if saved is not None and not _same_box(saved, given):
        raise InputError(f"{option}: {path} was trained for other {what} bounds than the env's")
    return given


def _policy_kwargs(field: dict[str, Any], path: Path, option: str) -> dict[str, Any]:
    """Policy kwargs from their printed form; classes only from an allow-list."""
    from torch import nn, optim

    out: dict[str, Any] = {}
    for key, value in field.items():
        if key.startswith(":"):
            continue
        m = _CLASS_REPR.match(value) if isinstance(value, str) else None
        name = m.group(1).rsplit(".", 1)[-1] if m else None
        if m and key == "activation_fn" and name in _ACTIVATIONS:
            out[key] = getattr(nn, name)
        elif m and key == "optimizer_class" and name in _OPTIMIZERS:
            out[key] = getattr(optim, name)
        elif m and key == "features_extractor_class" and name == "FlattenExtractor":
            from stable_baselines3.common.torch_layers import FlattenExtractor

            out[key] = FlattenExtractor
        elif m or (isinstance(value, str) and value.startswith("<")):
            raise InputError(f"{option}: {path}: unsupported policy_kwargs.{key} = {value}")
        else:
            out[key] = value
    return out


def safe_custom_objects(
    data: dict[str, Any],
    path: Path,
    spaces: tuple[Any, Any] = (None, None),
    schedules: dict[str, Any] | None = None,
    option: str = "model_path",
) -> dict[str, Any]:
    """A replacement for every pickled value of ``data``; refuse what has none."""
    from stable_baselines3.common.buffers import RolloutBuffer
    from stable_baselines3.common.policies import ActorCriticPolicy

    schedules = schedules or {}
    custom: dict[str, Any] = {}
    for key, value in data.items():
        if not (isinstance(value, dict) and ":serialized:" in value):
            continue
        if key in _RUNTIME_FIELDS:
            custom[key] = None
        elif key in _SCHEDULE_FIELDS:
            custom[key] = schedules.get(key, 0.0 if key != "clip_range_vf" else None)
        elif key == "policy_class":
            if not str(value.get("__init__", "")).startswith(
                "<function ActorCriticPolicy.__init__"
            ):
                raise InputError(
                    f"{option}: {path}: only MlpPolicy (ActorCriticPolicy) models load"
                )
            custom[key] = ActorCriticPolicy
        elif key == "policy_kwargs":
            custom[key] = _policy_kwargs(value, path, option)
        elif key in ("observation_space", "action_space"):
            given = spaces[0] if key == "observation_space" else spaces[1]
            custom[key] = _space(data, key, given, path, option)
        elif key == "rollout_buffer_class":
            custom[key] = RolloutBuffer
        else:
            raise InputError(
                f"{option}: {path} stores {key!r} as a pickle, which would run code when "
                "loaded; refusing it"
            )
    return custom


def load_ppo_safely(
    path: str | Path,
    spaces: tuple[Any, Any] = (None, None),
    env: Any = None,
    schedules: dict[str, Any] | None = None,
    option: str = "model_path",
    **kwargs: Any,
) -> Any:
    """``PPO.load`` with every pickled field replaced (see :func:`safe_custom_objects`).

    Parameters
    ----------
    spaces : (observation_space, action_space)
        The env's spaces: the model must match them (shape and bounds), else InputError.
    env : VecEnv, optional
        Passed to ``PPO.load`` (resume); its spaces are used when ``spaces`` is not given.
    schedules : dict, optional
        ``learning_rate`` / ``clip_range`` to continue training with (default: 0, inference).
    """
    from stable_baselines3 import PPO

    path = Path(path)
    data = read_zip_data(path, option)
    if env is not None and spaces == (None, None):
        spaces = (env.observation_space, env.action_space)
    custom = safe_custom_objects(data, path, spaces, schedules, option)
    try:
        return PPO.load(path, env=env, device="cpu", custom_objects=custom, **kwargs)
    except Exception as exc:
        raise InputError(
            f"{option}: {path} is not a readable PPO model: {type(exc).__name__}: {exc}"
        ) from None


def constant(value: float) -> Callable[[float], float]:
    """A constant schedule (a named function: nothing to pickle)."""
    return lambda _progress: value


# --------------------------------------------------------------------------- conversion
def convert_pickle(pkl: str | Path) -> Path:
    """Convert a VecNormalize pickle to ``.json`` beside it. Runs the pickle's code: trusted only."""
    import pickle

    pkl = Path(pkl)
    with open(pkl, "rb") as f:
        vn = pickle.load(f)  # noqa: S301  (explicitly requested by the user for a trusted file)
    return write_stats(vn, pkl.with_suffix(".json"))


def main(argv: list[str] | None = None) -> int:
    """``python -m agents.model_io FILE.pkl ...``: convert old statistics pickles to JSON."""
    args = sys.argv[1:] if argv is None else argv
    if not args or args[0] in ("-h", "--help"):
        print(
            "usage: python -m agents.model_io VECNORMALIZE.pkl ...\n"
            "Converts VecNormalize pickles to the JSON lrp-gym loads. Loading a pickle runs\n"
            "code stored in it: convert only files you trust (your own runs)."
        )
        return 0 if args else 2
    for name in args:
        print(f"wrote {convert_pickle(name)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
