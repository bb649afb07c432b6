"""How fast is a kidnap noticed, and does the restart settle right? (session 15)

For patrol seeds FIRST..LAST (pure pursuit, detections fidelity, a >= 3 m kidnap) prints the
frames the estimate stays converged on the old pose (before the lost test notices) and all
converged frames more than 0.3 m off within 15 frames of the kidnap (a restart that settles
on a wrong mode counts here), with the seeds over 2 frames. The per-seed measure is the
recovery tests' own (``tests/localization/test_loc_recovery.py``).

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/kidnap_notice.py 0 29 \\
        ['{"lost_test_clutter_probability": null}']
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "localization"))
from test_loc_recovery import _wrong_frames_after_kidnap  # noqa: E402


def main() -> None:
    first, last = int(sys.argv[1]), int(sys.argv[2])
    loc = json.loads(sys.argv[3]) if len(sys.argv) > 3 else {}
    seeds = range(first, last + 1)
    rows = [_wrong_frames_after_kidnap(s, {"localization": loc}) for s in seeds]
    for k, name in enumerate(("on the old pose", "wrong within 15 frames")):
        frames = [r[k] for r in rows]
        slow = [s for s, f in zip(seeds, frames, strict=True) if f > 2]
        print(f"{name}: {sum(frames)} frames in all, at most {max(frames)}; over 2: {slow}")


if __name__ == "__main__":
    main()
