"""How unequal the ghosts are: the return-mix survey's count per predicted ghost, per room
(docs/trust.md, session 27).

For generated rooms (``random_scenario(default_rng(seed))``) and the 2 + 2 paper layout: each
predicted ghost (a reflector via one face or a pair of faces, the rows of
``lrp_gym.localization.ghosts.GhostModel``), sorted by how many of the survey's returns it
explained, coloured by its face bounces; the likelihood's weight with ``ghost_weights:
surveyed`` and the equal share it had before. Prints how many ghosts hold half of the returns.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/ghost_weights_figure.py [--rooms 7,3,8,17] \
        [--out docs/ghost_weights.png]
"""

from __future__ import annotations

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from lrp_gym.config import load_scenario  # noqa: E402
from lrp_gym.experiments.scenarios import generated_room, reflector_kinds  # noqa: E402
from lrp_gym.localization.return_mix import return_mix  # noqa: E402
from lrp_gym.output import save_figure  # noqa: E402

FAST = {"radar": {"fidelity": "detections"}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rooms", default="7,3,8,17", help="generated room seeds, by commas")
    ap.add_argument("--poses", type=int, default=200, help="survey frames (the default's)")
    ap.add_argument("--out", default="docs/ghost_weights.png")
    args = ap.parse_args()
    rooms = [(f"room {s}", generated_room(int(s), FAST)) for s in args.rooms.split(",")]
    rooms.append(("2 + 2 paper layout", load_scenario("ipin2023-2types").with_overrides(FAST)))
    fig, axes = plt.subplots(1, len(rooms), figsize=(3.2 * len(rooms), 3.2), sharey=True)
    for ax, (label, cfg) in zip(np.atleast_1d(axes), rooms, strict=True):
        mix = return_mix(cfg, args.poses, seed=0)
        counts = np.asarray(mix.ghost_row_counts)
        bounces = np.asarray(mix.ghost_row_bounces)
        weights = mix.ghost_row_weights()
        order = np.argsort(-counts, kind="stable")
        ranks = np.arange(1, len(counts) + 1)
        for b, colour in ((1, "tab:blue"), (2, "tab:orange")):
            sel = bounces[order] == b
            ax.bar(ranks[sel], weights[order][sel], width=1.0, color=colour, label=f"{b} bounce")
        ax.axhline(1.0 / len(counts), color="k", lw=0.8, ls="--", label="equal share")
        ax.set_yscale("log")
        ax.set_xlabel("ghost, by survey count")
        kinds = reflector_kinds(cfg)
        ax.set_title(f"{label}\n{kinds}", fontsize=9)
        share = np.cumsum(np.sort(counts)[::-1]) / max(counts.sum(), 1)
        half = int(np.searchsorted(share, 0.5)) + 1
        print(
            f"{label} ({kinds}): {len(counts)} ghosts, {counts.sum()} returns, half in {half}, "
            f"never seen {int(np.sum(counts == 0))}; per ghost, 1 bounce "
            f"{counts[bounces == 1].mean():.2f}, 2 bounces {counts[bounces == 2].mean():.2f}"
        )
    np.atleast_1d(axes)[0].set_ylabel("share of the ghost probability")
    np.atleast_1d(axes)[0].legend(fontsize=8)
    fig.suptitle("Predicted ghosts weighted by the survey (200 frames)", fontsize=10)
    fig.tight_layout()
    save_figure(fig, args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
