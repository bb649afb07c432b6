"""Where the truth is when a converged estimate is wrong under clutter (docs/trust.md, session 19).

Pure pursuit on the env's default task with unmapped scatterers. At every converged step: the
particle weight within 0.3 m of the true position (the truth's mass) and how many particles
are there, and whether a minority mode (100 or more particles 0.5 m or more from the
estimate) is present. Prints percentiles for the right and the wrong steps, and per band of
the confidence, the wrong share with and without a minority mode beside the band's claim.

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/truth_in_cloud.py --seeds 7300-7399 [--severity 0.5]
"""

from __future__ import annotations

import numpy as np
from wrong_converged_features import default_task_steps, study_args  # the script beside this one

from lrp_gym.localization.metrics import CONFIDENTLY_WRONG_M

#: A minority mode: at least this many particles at least ``FAR_M`` from the estimate.
MINORITY_PARTICLES = 100
FAR_M = 0.5
BANDS = ((0.9, 0.95), (0.95, 0.99), (0.99, 1.0))


def converged_steps(seeds: range, severity: float, overrides: dict | None = None) -> np.ndarray:
    """One row per converged step: wrong, confidence, truth's mass, particles near the
    truth, particles, particles far from the estimate."""
    rows = []
    for step, info, amcl in default_task_steps(seeds, severity, overrides):
        if step == 0 or not info["converged"]:
            continue
        xy = amcl.particles[:, :2]
        w = amcl.weights / np.sum(amcl.weights)
        near = np.hypot(*(xy - np.asarray(info["true_pose"])[:2]).T) < CONFIDENTLY_WRONG_M
        far = np.hypot(*(xy - np.asarray(info["est_pose"])[:2]).T) >= FAR_M
        wrong = info["position_error_m"] > CONFIDENTLY_WRONG_M
        conf = info["localization_confidence"]
        rows.append((wrong, conf, w[near].sum(), near.sum(), len(w), far.sum()))
    return np.array(rows, float).reshape(-1, 6)


def main() -> None:
    args = study_args(__doc__)
    r = converged_steps(args.seeds, args.severity, args.overrides)
    wrong, conf, minority = r[:, 0] > 0, r[:, 1], r[:, 5] >= MINORITY_PARTICLES
    print(f"{len(r)} converged steps, {int(wrong.sum())} wrong (> {CONFIDENTLY_WRONG_M} m)")
    for name, sel in (("right", ~wrong), ("wrong", wrong)):
        if not sel.any():
            continue
        mass = " / ".join(f"{v:.3g}" for v in np.percentile(r[sel, 2], [10, 50, 90]))
        near = " / ".join(f"{v:.0f}" for v in np.percentile(r[sel, 3], [10, 50, 90]))
        print(
            f"{name}: truth's mass p10 / p50 / p90 {mass}; particles near the truth {near}; "
            f"none near it in {int((r[sel, 3] == 0).sum())}; a minority mode in "
            f"{int(minority[sel].sum())} of {int(sel.sum())}"
        )
    print("confidence band | minority mode: steps, wrong, claim | single mode: steps, wrong, claim")
    for lo, hi in BANDS:
        band = (conf >= lo) & ((conf < hi) if hi < 1.0 else (conf <= hi))
        cells = []
        for sel in (band & minority, band & ~minority):
            claim = f"{1.0 - conf[sel].mean():.3f}" if sel.any() else "-"
            cells.append(f"{int(sel.sum())}, {int((sel & wrong).sum())}, {claim}")
        print(f"{lo:.2f}-{hi:.2f} | {cells[0]} | {cells[1]}")


if __name__ == "__main__":
    main()
