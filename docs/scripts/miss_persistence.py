"""Do the radar's misses of a reflector in view repeat from frame to frame?

Pure pursuit on the env's default task (detections fidelity), optionally in the paper room
with the obstacle-room box and with unmapped clutter: over the reflectors in view of the true
position, the share of frames whose fingerprint holds no distance within 0.15 m of the
reflector's (a miss) and the same share among frames that follow a miss of that reflector;
then the correlation of the miss indicators, ``(P(miss | miss) - P(miss)) / (1 - P(miss))``, one
and two frames apart, by the distance the robot moved in between.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/miss_persistence.py SEVERITY FIRST_SEED \
        END_SEED OBSTACLE   # e.g. 0.5 7300 7360 1
"""

import sys

import gymnasium as gym
import numpy as np

import lrp_gym  # noqa: F401  (registers the ids)
from agents.pure_pursuit import PurePursuitPolicy
from lrp_gym.world.reflector_view import reflector_view

BOX = {"min": [0.8, 1.4, 0.0], "max": [2.2, 2.6, 1.0]}
TOLERANCE_M = 0.15
#: Edges (m) of the bins of the distance moved between the two frames compared.
MOVED_EDGES_M = (0.0, 0.05, 0.1, 0.2, 0.4, np.inf)


def _episode(env, policy, seed: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per frame: (true xy, reflectors in view, reflectors missed)."""
    core = env.unwrapped.core
    world = core.world
    room, lay, h, r_max = world.room, world.layout, world.mount_height_m, world.fmcw.max_range_m
    policy.reset()
    obs, info = env.reset(seed=seed)
    done, out = False, []
    while not done:
        obs, _, terminated, truncated, info = env.step(policy.act(obs))
        done = terminated or truncated
        xy = np.asarray(info["true_pose"])[:2]
        fp = core.frames[0].fingerprint
        z = np.concatenate([np.asarray(d) for d in fp.distances_m]) if fp else np.zeros(0)
        in_view = reflector_view(room, lay, h, r_max, xy[None]).in_view[:, 0]
        d = world.true_distances_m(xy)
        missed = np.array([not np.any(np.abs(z - dj) < TOLERANCE_M) for dj in d])
        out.append((xy, in_view, missed))
    return out


def _correlations(frames_per_episode, p_miss: float, lag: int) -> list[str]:
    """The miss correlation ``lag`` frames apart, per bin of the distance moved."""
    edges = np.asarray(MOVED_EDGES_M)
    pairs, repeats = np.zeros(len(edges) - 1), np.zeros(len(edges) - 1)
    for frames in frames_per_episode:
        for (xy0, view0, miss0), (xy1, view1, miss1) in zip(frames, frames[lag:]):
            k = np.searchsorted(edges, np.hypot(*(xy1 - xy0)), side="right") - 1
            both = view0 & view1 & miss0
            pairs[k] += both.sum()
            repeats[k] += (both & miss1).sum()
    rows = []
    for k in range(len(pairs)):
        if pairs[k] >= 20:
            rho = repeats[k] / pairs[k]
            lam = (rho - p_miss) / (1.0 - p_miss)
            rows.append(
                f"  lag {lag}, moved {edges[k]:.2f}-{edges[k + 1]:.2f} m: P(miss | miss) "
                f"{rho:.3f} of {int(pairs[k])}, correlation {lam:.2f}"
            )
    return rows


def main() -> None:
    severity = float(sys.argv[1])
    seeds = range(int(sys.argv[2]), int(sys.argv[3]))
    over: dict = {"room": {"obstacles": [BOX]}} if sys.argv[4] == "1" else {}
    if severity > 0.0:
        over["perturbations"] = {"clutter": {"severity": severity}}
    env = gym.make("LRPRadarNavFast-v0", task_mode="goal", overrides=over)
    policy = PurePursuitPolicy.from_env(env)
    episodes = [_episode(env, policy, seed) for seed in seeds]
    frames = misses = after_miss = misses_after_miss = 0
    for ep in episodes:
        last = None
        for _xy, in_view, missed in ep:
            for j in np.flatnonzero(in_view):
                frames += 1
                misses += missed[j]
                if last is not None and last[0][j] and last[1][j]:
                    after_miss += 1
                    misses_after_miss += missed[j]
            last = (in_view, missed)
    p_miss = misses / frames
    print(
        f"P(miss) {p_miss:.3f} of {frames} reflector-frames in view, "
        f"P(miss | missed the frame before) {misses_after_miss / max(after_miss, 1):.3f} "
        f"of {after_miss}"
    )
    for lag in (1, 2):
        print("\n".join(_correlations(episodes, p_miss, lag)))


if __name__ == "__main__":
    main()
