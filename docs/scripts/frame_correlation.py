"""How long does a reflector's range error persist along the path? (session 16)

Pure pursuit drives the env's default task; in every frame each reflector's true distance is
compared with the nearest measured distance of its type (``range_residuals.py``). Pairs of
frames up to eight apart in an episode are binned by the distance the robot drove between
them, and the correlation of the two errors (both within 7.5 cm) is printed per bin: what
``likelihood_correlation_m`` models.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/frame_correlation.py [--episodes 30] \
        [--severity 0.5] [--env LRPRadarNav-v0]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from range_residuals import driven_frames, reflector_residuals  # noqa: E402

BINS_M = ((0.0, 0.02), (0.02, 0.06), (0.06, 0.1), (0.1, 0.2), (0.2, 0.4), (0.4, 0.8), (0.8, 5.0))


def error_pairs(env_id: str, episodes: int, severity: float, seed: int) -> np.ndarray:
    """Rows (distance driven between the frames in m, error 1, error 2)."""
    history: dict[int, list] = {}
    for k, base in driven_frames(env_id, episodes, severity, seed):
        gated = base.tracker.gated_fingerprint()
        errors = reflector_residuals(base.localizer.model, gated, base.pose[:2])
        history.setdefault(k, []).append((base.pose[:2].copy(), errors))
    pairs = []
    for frames in history.values():
        for i, (p1, r1) in enumerate(frames):
            for p2, r2 in frames[i + 1 : i + 9]:
                if len(r2) != len(r1):  # a suspect reflector left the map in between
                    continue
                d = float(np.hypot(*(p1 - p2)))
                both = (np.abs(r1) < 0.075) & (np.abs(r2) < 0.075)
                pairs += [(d, a, b) for a, b in zip(r1[both], r2[both], strict=True)]
    return np.array(pairs).reshape(-1, 3)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--env", default="LRPRadarNavFast-v0")
    ap.add_argument("--episodes", type=int, default=30)
    ap.add_argument("--severity", type=float, default=0.0, help="clutter severity")
    ap.add_argument("--seed", type=int, default=7000)
    args = ap.parse_args()
    p = error_pairs(args.env, args.episodes, args.severity, args.seed)
    print(f"{args.env}, clutter {args.severity}, {args.episodes} episodes from seed {args.seed}")
    for lo, hi in BINS_M:
        m = (p[:, 0] >= lo) & (p[:, 0] < hi)
        if m.sum() >= 20:
            corr = np.corrcoef(p[m, 1], p[m, 2])[0, 1]
            print(f"driven {lo:.2f}-{hi:.2f} m: {m.sum():6d} pairs, correlation {corr:5.2f}")


if __name__ == "__main__":
    main()
