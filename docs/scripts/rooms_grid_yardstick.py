"""The Bayes yardstick on the generated rooms where AMCL misses 0.15 m.

``lrp-gym reproduce-paper --random-rooms 20 --localizer grid`` runs the grid filter on every
room; it is slow (minutes per room on one core), and only the rooms where AMCL fails can break
"AMCL localises wherever the grid filter does". This script runs those rooms (default: the
five that fail in README's ``random_rooms`` row) with a coarser grid (0.1 m, 10 degrees)
and prints one JSON line per room, then the summary.

    python docs/scripts/rooms_grid_yardstick.py [ROOM_SEED ...]
"""

from __future__ import annotations

import json
import sys

from lrp_gym.experiments.rooms import summary, sweep

GRID = {"localization": {"grid_cell_m": 0.1, "grid_cell_deg": 10.0}, "radar": {"noise": False}}


def main(seeds: list[int]) -> None:
    def show(r) -> None:
        print(
            json.dumps(
                {
                    "seed": r.seed,
                    "kinds": r.kinds,
                    "amcl_radar_m": r.amcl_radar_m,
                    "grid_radar_m": r.grid_radar_m,
                }
            ),
            flush=True,
        )

    results = sweep(seeds, overrides=GRID, localizer="grid", progress=show)
    data = summary(results)
    data.pop("per_room")
    print(json.dumps(data, indent=1))


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [6, 7, 8, 16, 17])
