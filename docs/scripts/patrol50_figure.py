"""The 50-episode patrol matrix of docs/robustness.md as one heat map per layout.

The matrix is run one perturbation per command (each with its own severities, see
docs/robustness.md); this merges those JSON files (docs/robustness_patrol50/SCENARIO-*.json,
one baseline row) and draws them with ``lrp-gym robustness --plot``'s figure:

    python docs/scripts/patrol50_figure.py ipin2023-patrol ipin2023-2types-patrol
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from lrp_gym.experiments.robustness import BASELINE, plot_matrix
from lrp_gym.output import save_figure

HERE = Path(__file__).resolve().parent.parent
ORDER = ("clutter", "kidnap", "missed", "slip", "displaced", "shadowing")


def merged(scenario: str) -> dict:
    """One matrix from the per-perturbation files of ``scenario``."""
    cells, result = [], None
    for name in ORDER:
        path = HERE / "robustness_patrol50" / f"{scenario}-{name}.json"
        if not path.exists():
            continue
        result = json.loads(path.read_text())
        for cell in result["cells"]:
            if cell["perturbation"] != BASELINE or not cells:
                cells.append(cell)
    if result is None:
        raise SystemExit(f"no JSON for {scenario} in {HERE / 'robustness_patrol50'}")
    return {**result, "cells": cells}


if __name__ == "__main__":
    for scenario in sys.argv[1:] or ["ipin2023-patrol", "ipin2023-2types-patrol"]:
        fig = plot_matrix(merged(scenario))
        fig.suptitle(
            f"{scenario}: 50 episodes per cell, pure pursuit, detections fidelity", fontsize=9
        )
        out = save_figure(fig, HERE / f"robustness_patrol50_{scenario}.png")
        print(f"wrote {out}")
