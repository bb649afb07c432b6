"""AMCL on one generated room's path over several runs, with the ghosts weighted by the survey
and equally (docs/trust.md, session 27): the README's ``random_rooms`` row runs each room once.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/room_path_runs.py 18 --runs 4
"""

from __future__ import annotations

import argparse

from lrp_gym.experiments.reproduce import reproduce
from lrp_gym.experiments.scenarios import generated_room


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("room", type=int, help="generated room seed")
    ap.add_argument("--runs", type=int, default=4)
    args = ap.parse_args()
    for weights in ("surveyed", "uniform"):
        cfg = generated_room(args.room, {"localization": {"ghost_weights": weights}})
        err = reproduce(cfg, runs=args.runs, seed=0).amcl_errors_m
        runs = ", ".join(f"{e:.3f}" for e in err.mean(axis=1))
        print(f"ghost_weights {weights}: mean {err.mean():.3f} m (runs {runs})")


if __name__ == "__main__":
    main()
