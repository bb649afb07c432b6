"""CPU per frame of the lost test's second statistic on the paper room's grid (session 13).

Times, in process CPU time, the cloud's neighbourhood (``GridAlternative.far_from``) at 800
and 10 000 particles and one predict-and-update of the filter (``GridAlternative.update``).

    PYTHONPATH=$PWD .venv/bin/python docs/scripts/lost_alternative_cost.py
"""

from __future__ import annotations

import time

import numpy as np

from lrp_gym.config import load_scenario
from lrp_gym.localization.amcl import Amcl
from lrp_gym.world import World


def per_call_ms(fn, seconds: float = 1.0) -> float:
    """Mean CPU milliseconds per call of ``fn`` over about ``seconds``."""
    fn()
    start, n = time.process_time(), 0
    while time.process_time() - start < seconds:
        fn()
        n += 1
    return 1e3 * (time.process_time() - start) / n


def main() -> None:
    cfg = load_scenario("ipin2023")
    amcl = Amcl(World.from_config(cfg), cfg.localization)
    alt = amcl.lost.alternative
    rng = np.random.default_rng(0)
    loglik = 3.0 * rng.normal(size=len(amcl.grid))
    for n in (800, 10_000):
        xy, w = rng.uniform(0.5, 4.0, (n, 2)), np.ones(n)
        print(
            f"far_from, {n} particles: {per_call_ms(lambda xy=xy, w=w: alt.far_from(xy, w)):.3f} ms"
        )

    def update() -> None:
        alt.move(0.03)
        alt.update(loglik)

    print(f"update ({len(amcl.grid)} cells): {per_call_ms(update):.3f} ms")


if __name__ == "__main__":
    main()
