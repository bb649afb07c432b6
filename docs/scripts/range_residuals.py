"""How far are the distances AMCL weighs from the reflectors' true distances? (session 15)

Pure pursuit drives the env's default task; in every frame each RCS-gated detection (what
AMCL weighs) is compared with the nearest true distance of a reflector of its type, at the
robot's true position and, as the chance level, at a random free position. Prints the share
of residuals within 1 mm, 1, 3 and 7.5 cm (7.5 cm is the range resolution, once AMCL's
``measurement_std_m``), and the 68th percentile of those within 7.5 cm. The same for every
reflector's true distance against the nearest measured one (its own return, if any).

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/range_residuals.py [--episodes 12] \
        [--severity 0.5] [--env LRPRadarNav-v0]
"""

from __future__ import annotations

import argparse
from collections.abc import Iterator

import gymnasium as gym
import numpy as np

import lrp_gym  # noqa: F401  (registers the ids)
from agents.pure_pursuit import PurePursuitPolicy


def nearest_residuals(model, fingerprint, xy: np.ndarray) -> np.ndarray:
    """Signed residual of every distance to the nearest expected one of its type at ``xy``."""
    expected = model.expected(np.asarray(xy, float)[None, :])
    out = []
    for name, z in zip(fingerprint.type_names, fingerprint.distances_m, strict=True):
        if len(z) == 0 or name not in model.type_names:
            continue
        e = expected[model.type_names.index(name)][:, 0]
        if len(e) == 0:
            continue
        r = np.asarray(z, float)[:, None] - e[None, :]
        out.append(r[np.arange(len(z)), np.argmin(np.abs(r), axis=1)])
    return np.concatenate(out) if out else np.zeros(0)


def reflector_residuals(model, fingerprint, xy: np.ndarray) -> np.ndarray:
    """Signed residual of every reflector's true distance at ``xy`` to the nearest measured
    distance of its type (inf where its type has none)."""
    expected = model.expected(np.asarray(xy, float)[None, :])
    measured = dict(zip(fingerprint.type_names, fingerprint.distances_m, strict=True))
    out = []
    for name, e in zip(model.type_names, expected, strict=True):
        z = np.asarray(measured.get(name, ()), float)
        if len(z) == 0:
            out.append(np.full(len(e), np.inf))
            continue
        r = z[None, :] - e[:, 0][:, None]
        out.append(r[np.arange(len(e)), np.argmin(np.abs(r), axis=1)])
    return np.concatenate(out) if out else np.zeros(0)


def driven_frames(env_id: str, episodes: int, severity: float, seed: int) -> Iterator[tuple]:
    """``(episode, env.unwrapped)`` after every step of ``episodes`` default-task runs of pure
    pursuit (seeds ``seed``, ``seed + 1``, ...), with clutter of ``severity``."""
    over = {"perturbations": {"clutter": {"severity": severity}}} if severity > 0 else {}
    env = gym.make(env_id, task_mode="goal", overrides=over)
    policy = PurePursuitPolicy.from_env(env)
    for k in range(episodes):
        policy.reset()
        obs, _ = env.reset(seed=seed + k)
        done = False
        while not done:
            obs, _, terminated, truncated, _ = env.step(policy.act(obs))
            done = terminated or truncated
            yield k, env.unwrapped
    env.close()


def collect(env_id: str, episodes: int, severity: float, seed: int) -> dict[str, np.ndarray]:
    """Residuals over ``episodes`` default-task runs: every measured distance against the
    nearest true one at the robot's position and at a random one, and every reflector's true
    distance against the nearest measured one."""
    rng = np.random.default_rng(seed)
    rows: dict[str, list[np.ndarray]] = {"measured, true": [], "measured, random": []}
    rows["reflector, true"] = []
    for _, base in driven_frames(env_id, episodes, severity, seed):
        model, gated = base.localizer.model, base.tracker.gated_fingerprint()
        rows["measured, true"].append(nearest_residuals(model, gated, base.pose[:2]))
        elsewhere = base.localizer.uniform_particles(1, rng)[0, :2]
        rows["measured, random"].append(nearest_residuals(model, gated, elsewhere))
        rows["reflector, true"].append(reflector_residuals(model, gated, base.pose[:2]))
    return {name: np.concatenate(r) for name, r in rows.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--env", default="LRPRadarNavFast-v0")
    ap.add_argument("--episodes", type=int, default=12)
    ap.add_argument("--severity", type=float, default=0.0, help="clutter severity")
    ap.add_argument("--seed", type=int, default=7000)
    args = ap.parse_args()
    rows = collect(args.env, args.episodes, args.severity, args.seed)
    print(f"{args.env}, clutter {args.severity}, {args.episodes} episodes from seed {args.seed}")
    print("residual of          count   <1 mm  <1 cm  <3 cm  <7.5 cm  p68 within 7.5 cm")
    for name, r in rows.items():
        a = np.abs(r)
        shares = "  ".join(f"{100 * np.mean(a < t):4.0f} %" for t in (0.001, 0.01, 0.03, 0.075))
        inner = a[a < 0.075]
        p68 = 100 * np.percentile(inner, 68) if len(inner) else np.nan
        print(f"{name:17s}  {len(r):7d}  {shares}  {p68:10.1f} cm")


if __name__ == "__main__":
    main()
