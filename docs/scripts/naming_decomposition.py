"""Where a moved reflector's evidence goes: its displacement statistic, one change at a time.

Records EPISODES patrol episodes with one reflector moved by SHIFT metres (as
``monitor_replay.py`` does: seeds 0..EPISODES-1, the monitor's verdicts not fed back) and, for
the seeds listed, feeds the same monitor five versions of each frame:

- ``ideal``: the true pose, only the reflectors' own returns (2.6 cm noise; the yardstick);
- ``estimate, own``: the estimated pose, only the judged reflectors' own returns;
- ``estimate, own, others``: the estimated pose, the frame's other returns and the moved
  reflector's own return (ideal, so that a miss does not count);
- ``true pose, real``: the true pose with the real frame;
- ``real``: the recorded frame as the monitor saw it.

Prints the moved reflector's statistic every 5 frames up to the naming budget. The first
three versions carry no radial velocities, so the likelihood test weighs their distances only;
the last two weigh the recorded Doppler too (``displacement_doppler_std_mps``).

    python docs/scripts/naming_decomposition.py ipin2023-patrol 0.25 50 19,36,45,49
"""

from __future__ import annotations

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from monitor_replay import record  # noqa: E402

from lrp_gym.experiments.robustness import SUSPECT_BUDGET_FRAMES  # noqa: E402
from lrp_gym.localization.monitor_frame import MonitorFrame, nearest_residuals  # noqa: E402
from lrp_gym.localization.reflector_monitor import ReflectorMonitor  # noqa: E402

VERSIONS = ("ideal", "estimate, own", "estimate, own, others", "true pose, real", "real")


def _frame(predicted, judged, bearing, z) -> MonitorFrame:
    z = np.sort(z)
    return MonitorFrame(judged, nearest_residuals(predicted, z), bearing, predicted, z)


def decompose(ep: dict, rng: np.random.Generator) -> dict[str, list[float]]:
    """The moved reflector's statistic every 5 frames, per version of the frames."""
    world = ep["world"]
    true_pos = world.layout.positions_m.copy()
    moved = sorted(ep["moved"])
    true_pos[moved] += ep["offsets_m"]
    j = moved[0]
    mons = {v: ReflectorMonitor(world, ep["cfg"], ep["max_range_m"]) for v in VERSIONS}
    out: dict[str, list[float]] = {v: [] for v in VERSIONS}
    frames = zip(ep["frames"][:SUSPECT_BUDGET_FRAMES], ep["true_poses"], strict=False)
    for k, ((est, gated, others, speed, det), pose) in enumerate(frames, start=1):
        radar = world.radar_position(np.asarray(pose[:2], float))
        own = np.linalg.norm(true_pos - radar, axis=1) + rng.normal(0.0, 0.026, len(true_pos))
        predicted, seen, bearing, _ = mons["ideal"]._geometry(pose[:2])
        mons["ideal"].accumulate(_frame(predicted, seen, bearing, own[seen]))
        real = mons["real"].observe(
            SimpleNamespace(converged=est.converged, pose=est.pose), gated, others, speed, det
        )
        if real is not None:
            mons["real"].accumulate(real)
            p, judged, b = real.predicted_m, real.judged, real.bearing
            mons["estimate, own"].accumulate(_frame(p, judged, b, own[judged]))
            z = real.distances_m
            rest = z[np.abs(z - own[j]) >= 0.06]  # the frame without the moved one's return
            z = np.concatenate([rest, own[j : j + 1]]) if judged[j] else z
            mons["estimate, own, others"].accumulate(_frame(p, judged, b, z))
        true_view = SimpleNamespace(converged=est.converged, pose=np.asarray(pose))
        frame = mons["true pose, real"].observe(true_view, gated, others, speed, det)
        if frame is not None:
            mons["true pose, real"].accumulate(frame)
        if k % 5 == 0:
            for v, mon in mons.items():
                out[v].append(round(float(mon.displacement.statistic[j]), 1))
    return out


def main(scenario: str, shift_m: float, episodes: int, seeds: list[int]) -> None:
    recorded = record(scenario, "displaced_reflector", shift_m, episodes)
    rng = np.random.default_rng(0)
    for seed in seeds:
        ep = recorded[seed]
        print(f"seed {seed}: reflector {sorted(ep['moved'])} moved by {ep['offsets_m'][0, :2]} m")
        for version, values in decompose(ep, rng).items():
            print(f"  {version:24s} statistic at frames 5, 10, ...: {values}")


if __name__ == "__main__":
    main(
        sys.argv[1], float(sys.argv[2]), int(sys.argv[3]), [int(s) for s in sys.argv[4].split(",")]
    )
