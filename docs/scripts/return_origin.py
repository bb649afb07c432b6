"""Where the reflector-like returns come from, per room (docs/trust.md, session 25).

For the paper rooms and the generated rooms ``random_scenario(default_rng(seed))``: the shares
of the returns in the tracker's RCS windows that are a reflector's direct return, a reflector
seen via the room's faces (a ghost) or the room's own surfaces, measured by
:func:`lrp_gym.localization.return_mix.return_mix` at random free poses, beside the
likelihood's fixed mixture (``structure_probability`` 0.6, ``ghost_probability`` 0.1 of the
returns the map explains).

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/return_origin.py [--rooms 0-19] [--poses 200] \
        [--fidelity detections]
"""

from __future__ import annotations

import argparse

from lrp_gym.config import load_scenario
from lrp_gym.experiments.scenarios import generated_room, reflector_kinds
from lrp_gym.localization.return_mix import return_mix


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rooms", default="0-19", help="generated room seeds FIRST-LAST")
    ap.add_argument("--poses", type=int, default=200)
    ap.add_argument("--fidelity", default="detections")
    args = ap.parse_args()
    first, last = (int(v) for v in args.rooms.split("-"))
    over = {"radar": {"fidelity": args.fidelity}}
    named = [(name, load_scenario(name)) for name in ("ipin2023", "ipin2023-2types")]
    rooms = [(f"room {s}", generated_room(s)) for s in range(first, last + 1)]
    print("room | kinds | direct | ghost | structure | other | -> structure_p, ghost_p")
    for label, cfg in named + rooms:
        cfg = cfg.with_overrides(over)
        kinds = reflector_kinds(cfg)
        mix = return_mix(cfg, args.poses, seed=0)
        s, g = mix.map_return_probabilities()
        print(
            f"{label} | {kinds} | {mix.direct:.2f} | {mix.ghost:.2f} | {mix.structure:.2f} | "
            f"{mix.other:.2f} | {s:.2f}, {g:.2f}"
        )


if __name__ == "__main__":
    main()
