"""Per-frame traces of AMCL's global start on the default task (issue #17, session 10).

Drives pure pursuit on the goal task (the trust rows' episodes: ``evaluate --task goal
--fidelity detections``) and prints, for every frame of the first ``--frames`` of each
episode: the particle count before and after resampling, the effective sample size, the
occupied KLD bins, the posterior mass near the true pose (position within 0.2 m; position and
heading within 0.35 rad), the estimate's error and confidence. For the global start's frame it
also prints where the true position ranks on the start grid, the proposal's mass within 0.2 m
of it and how many of the drawn particles land there (and with the right heading).

```bash
PYTHONPATH=$PWD .venv/bin/python docs/scripts/start_trace.py ipin2023 --seeds 7000-7009 \
    [--set localization.initial_particles=2000]
```
"""

from __future__ import annotations

import argparse

import numpy as np

import lrp_gym  # noqa: F401  (registers the ids)
from lrp_gym.commands._common import overrides
from lrp_gym.experiments import episodes as ep
from lrp_gym.localization.amcl import Amcl
from lrp_gym.localization.proposal import MeasurementGrid

NEAR_M = 0.2
NEAR_RAD = 0.35
ROWS: list[dict] = []
TRUTH: dict = {}


def _near(particles: np.ndarray, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Masks of particles within ``NEAR_M`` of ``pose`` and also within ``NEAR_RAD``."""
    pos = np.hypot(*(particles[:, :2] - pose[:2]).T) < NEAR_M
    dth = np.abs((particles[:, 2] - pose[2] + np.pi) % (2 * np.pi) - np.pi)
    return pos, pos & (dth < NEAR_RAD)


def _hooked_global_start(orig):
    def wrapper(self, fingerprint, rng, speed_mps):
        pose = TRUTH["env"].core.pose[0]
        cell_ll = self.start_grid.log_likelihood(self.model, fingerprint)
        temp = cell_ll * self.cfg.likelihood_exponent
        p = np.exp(temp - temp.max())
        p /= p.sum()
        d = np.hypot(*(self.start_grid.centres_m - pose[:2]).T)
        true_cell = int(np.argmin(d))
        w = orig(self, fingerprint, rng, speed_mps)
        pos, both = _near(self.particles, pose)
        wn = w / w.sum()
        ROWS.append(
            dict(
                kind="start",
                i=TRUTH["i"],
                cells=len(cell_ll),
                rank=int(np.sum(cell_ll > cell_ll[true_cell])),
                prop_mass=float(p[d < NEAR_M].sum()),
                best_cell_err=float(d[int(np.argmax(cell_ll))]),
                n=len(w),
                drawn_pos=int(pos.sum()),
                drawn_both=int(both.sum()),
                w_pos=float(wn[pos].sum()),
                w_both=float(wn[both].sum()),
                ess=float(1.0 / np.dot(wn, wn)),
            )
        )
        return w

    return wrapper


def _hooked_resample(orig):
    def wrapper(self, rng):
        pose = TRUTH["env"].core.pose[0]
        pos, both = _near(self.particles, pose)
        before = len(self.weights)
        orig(self, rng)
        pos2, both2 = _near(self.particles, pose)
        TRUTH["resample"] = dict(
            n_before=before,
            n_after=len(self.weights),
            k_bins=self.last_k_bins,
            m_pos=float(self.weights[pos2].sum()),
            m_both=float(self.weights[both2].sum()),
            copies_both=int(both2.sum()),
            pre_pos=float(TRUTH["w"][pos].sum()),
            pre_both=float(TRUTH["w"][both].sum()),
        )

    return wrapper


def _hooked_update(orig):
    def wrapper(self, odometry, fingerprint, rng, **kw):
        TRUTH.pop("resample", None)
        n0 = len(self.particles)
        cls = type(self)
        inner = cls._resample

        def resample(s, r):
            TRUTH["w"] = s.weights
            inner(s, r)

        cls._resample = resample
        try:
            est = orig(self, odometry, fingerprint, rng, **kw)
        finally:
            cls._resample = inner
        pose = TRUTH["env"].core.pose[0]
        err = float(np.hypot(*(est.pose[:2] - pose[:2])))
        row = dict(kind="frame", i=TRUTH["i"], n0=n0, ess=est.ess, err=err, conf=est.confidence)
        TRUTH["i"] += 1
        row.update(conv=est.converged, n_modes=est.n_modes, p_lost=self.lost.p_lost)
        row.update(TRUTH.get("resample", {}))
        ROWS.append(row)
        return est

    return wrapper


def install() -> None:
    """Wrap :class:`Amcl`'s start, update and resampling to record the rows."""
    Amcl._global_start = _hooked_global_start(Amcl._global_start)
    Amcl._resample = _hooked_resample(Amcl._resample)
    Amcl.update = _hooked_update(Amcl.update)


def _fmt(row: dict) -> str:
    if row["kind"] == "start":
        return (
            "  start at frame {i}: {cells} cells, true cell rank {rank}, proposal mass <0.2 m {prop_mass:.3f},"
            " best cell {best_cell_err:.2f} m off; {n} drawn, {drawn_pos} within 0.2 m"
            " ({drawn_both} with heading), weight there {w_pos:.3f} ({w_both:.3f}),"
            " ESS {ess:.0f}".format(**row)
        )
    s = "  {i:3d} n {n0:5d} ESS {ess:7.0f} err {err:5.2f} conf {conf:.2f} conv {conv:d} modes {n_modes}".format(
        **row
    )
    if "n_after" in row:
        s += (
            " | resample k {k_bins:5d} -> n {n_after:5d}, mass near truth {pre_pos:.3f}/{pre_both:.3f}"
            " -> {m_pos:.3f}/{m_both:.3f} ({copies_both} copies)".format(**row)
        )
    return s


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", nargs="?", default="ipin2023")
    parser.add_argument("--seeds", default="7000-7004", help="FIRST-LAST")
    parser.add_argument("--frames", type=int, default=6, help="frames printed after a start")
    parser.add_argument("--full", action="store_true", help="run whole episodes (kidnaps)")
    parser.add_argument("--set", action="append", default=[], dest="sets")
    parser.add_argument("--start-cell", type=float, help="replace the start grid's spacing (m)")
    args = parser.parse_args()
    from agents import registry

    first, last = (int(s) for s in args.seeds.split("-"))
    over = overrides(args.scenario, args.sets, "detections")
    over.setdefault("task", {})["mode"] = "goal"
    env = ep.make_eval_env("pure-pursuit", None, args.scenario, overrides=over)
    policy = registry.make_agent("pure-pursuit", env)
    TRUTH["env"] = ep.nav_env(env)
    if args.start_cell is not None:
        amcl = TRUTH["env"].core.stacks[0].localizer
        size = amcl._size_xy
        amcl.start_grid = MeasurementGrid(size, args.start_cell, amcl._free, max_cells=160_000)
    install()
    for seed in range(first, last + 1):
        ROWS.clear()
        TRUTH["i"] = 0
        obs, _ = env.reset(seed=seed)
        policy.reset()
        done = False
        while not done and (args.full or TRUTH["i"] < args.frames):
            obs, _, term, trunc, _ = env.step(policy.act(obs))
            done = term or trunc
        print(f"seed {seed}")
        starts = [r["i"] for r in ROWS if r["kind"] == "start"]
        for row in ROWS:
            if any(0 <= row["i"] - s < args.frames for s in starts) or not args.full:
                print(_fmt(row))


if __name__ == "__main__":
    main()
