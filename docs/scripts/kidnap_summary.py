"""Summarise ``kidnap_replay.py`` outputs: recovery within 15 frames, with 95 % intervals.

Per file (one variant and severity): the kidnaps recovered within 15 frames (a kidnap whose
episode ends first counts as not recovered, as in the robustness matrix), the early
collisions (the episode ends in a collision within 3 frames of the jump, before the filter
could have re-localised), and the recovery among the kidnaps whose episode ran at least 15
frames after the jump.

```bash
.venv/bin/python docs/scripts/kidnap_summary.py base_sev1.txt ip2000_sev1.txt
```
"""

from __future__ import annotations

import re
import sys

from lrp_gym.experiments.intervals import wilson_interval

LINE = re.compile(
    r"seed (\d+): .*collision (True|False), recovered after (\w+), frames after kidnap (\d+)"
)
BUDGET = 15


def summarise(path: str) -> dict:
    rows = [m.groups() for m in map(LINE.search, open(path)) if m]
    recovered = [r != "None" and int(r) <= BUDGET for _, _, r, _ in rows]
    early = [c == "True" and int(after) <= 3 for _, c, _, after in rows]
    running = [int(after) >= BUDGET for *_, after in rows]
    kept = [rec for rec, run in zip(recovered, running, strict=True) if run]
    return {
        "n": len(rows),
        "recovered": sum(recovered),
        "early_collisions": sum(early),
        "running": len(kept),
        "recovered_running": sum(kept),
    }


def main() -> None:
    for path in sys.argv[1:]:
        s = summarise(path)
        lo, hi = wilson_interval(s["recovered"], s["n"])
        lo2, hi2 = wilson_interval(s["recovered_running"], s["running"])
        print(
            f"{path}: recovered {s['recovered']}/{s['n']} = {s['recovered'] / s['n']:.1%}"
            f" ({lo:.1%}-{hi:.1%}); early collisions {s['early_collisions']};"
            f" among the {s['running']} still running 15 frames after:"
            f" {s['recovered_running'] / max(s['running'], 1):.1%} ({lo2:.1%}-{hi2:.1%})"
        )


if __name__ == "__main__":
    main()
