"""How trustworthy a localiser was over episodes: localised share, time to localise,
confidently-wrong rate and the reliability of its confidence."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

#: A position error below this counts as localised (metres).
LOCALISED_M = 0.2
#: A converged estimate further off than this is confidently wrong (metres).
CONFIDENTLY_WRONG_M = 0.3
#: An episode whose estimate stays converged and wrong this many frames in a row was stuck.
STUCK_WRONG_FRAMES = 10


def longest_wrong_stretch(
    errors_m: np.ndarray, converged: np.ndarray, wrong_m: float = CONFIDENTLY_WRONG_M
) -> int:
    """The longest run of consecutive frames that are converged and off by more than
    ``wrong_m`` (0 if none). A per-episode view of trust: the pooled share of wrong steps is
    dominated by the few episodes that stay stuck on a wrong pose for a hundred frames."""
    bad = np.asarray(converged, bool) & (np.asarray(errors_m, float) > wrong_m)
    if not bad.any():
        return 0
    # Run lengths from the indices where a run starts and ends.
    edges = np.diff(np.concatenate([[0], bad.astype(np.int8), [0]]))
    return int(np.max(np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)))


def frames_to_localised(errors_m: np.ndarray, localised_m: float = LOCALISED_M) -> int | None:
    """Index of the first frame with an error below ``localised_m`` (None if never)."""
    hit = np.flatnonzero(np.asarray(errors_m) < localised_m)
    return int(hit[0]) if len(hit) else None


def stuck_episodes(episodes: Sequence[tuple[np.ndarray, np.ndarray]]) -> int:
    """How many of the ``(errors_m, converged)`` episodes have :data:`STUCK_WRONG_FRAMES` or
    more converged, wrong frames in a row (:func:`longest_wrong_stretch`)."""
    return sum(longest_wrong_stretch(e, c) >= STUCK_WRONG_FRAMES for e, c in episodes)


#: Confidence bin edges of :func:`reliability`: finer near 1, where ``settled`` (0.9) and
#: ``converged`` (0.99) start and where a confidence's claim (1 - c: how often it may be
#: wrong) is a few per cent.
RELIABILITY_EDGES = (0.0, 0.2, 0.4, 0.6, 0.8, 0.9, 0.95, 0.99, 1.0)


def reliability(
    confidence: np.ndarray,
    errors_m: np.ndarray,
    bins: int | Sequence[float] = RELIABILITY_EDGES,
    localised_m: float = LOCALISED_M,
    wrong_m: float = CONFIDENTLY_WRONG_M,
) -> list[dict[str, float | int | None]]:
    """Reliability diagram: per confidence bin, the steps in it, their localised share and
    their wrong share.

    ``bins`` is the bins' edges from 0 to 1 (default :data:`RELIABILITY_EDGES`) or a number of
    equal bins; a confidence of 1 falls in the last bin. A calibrated confidence has
    ``localised_share`` close to the bin's mean confidence; ``wrong_share`` (off by more than
    ``wrong_m``, as the confidently-wrong rate counts) is what a confidence near 1 must keep
    below ``1 - mean_confidence``.
    """
    confidence = np.asarray(confidence, dtype=float)
    err = np.asarray(errors_m, dtype=float)
    ok = err < localised_m
    wrong = err > wrong_m
    edges = np.linspace(0.0, 1.0, bins + 1) if isinstance(bins, int) else np.asarray(bins, float)
    if edges[0] != 0.0 or edges[-1] != 1.0 or np.any(np.diff(edges) <= 0.0):
        raise ValueError(f"bins: edges must rise from 0 to 1, got {list(edges)}")
    n_bins = len(edges) - 1
    idx = np.clip(np.digitize(confidence, edges[1:-1]), 0, n_bins - 1)
    out = []
    for b in range(n_bins):
        sel = idx == b
        n = int(sel.sum())
        out.append(
            {
                "lo": float(edges[b]),
                "hi": float(edges[b + 1]),
                "steps": n,
                "mean_confidence": float(confidence[sel].mean()) if n else None,
                "localised_share": float(ok[sel].mean()) if n else None,
                "wrong_share": float(wrong[sel].mean()) if n else None,
            }
        )
    return out


def trust_metrics(
    errors_m: Sequence[np.ndarray],
    converged: Sequence[np.ndarray],
    confidence: Sequence[np.ndarray] | None = None,
) -> dict[str, object]:
    """Per-episode and pooled trust metrics of a localiser.

    Parameters
    ----------
    errors_m, converged, confidence : sequences of arrays, one per episode
        Position error, convergence flag and confidence at each step.

    Returns
    -------
    dict
        ``time_localised`` (pooled share of steps), ``mean_episode_time_localised``,
        ``median_frames_to_localised`` (episodes never localised count as their length),
        ``never_localised_rate``, ``confidently_wrong_rate`` (share of converged steps off by
        more than :data:`CONFIDENTLY_WRONG_M`), ``stuck_wrong_rate`` (share of episodes with
        :data:`STUCK_WRONG_FRAMES` or more such steps in a row), ``converged_share`` and, with
        ``confidence``,
        ``reliability`` (:func:`reliability`).
    """
    err = np.concatenate([np.asarray(e, float) for e in errors_m]) if errors_m else np.zeros(0)
    conv = np.concatenate([np.asarray(c, bool) for c in converged]) if converged else np.zeros(0)
    first = [frames_to_localised(e) for e in errors_m]
    frames = [f if f is not None else len(e) for f, e in zip(first, errors_m)]
    out: dict[str, object] = {
        "time_localised": float(np.mean(err < LOCALISED_M)) if err.size else None,
        "mean_episode_time_localised": (
            float(np.mean([np.mean(np.asarray(e) < LOCALISED_M) for e in errors_m if len(e)]))
            if err.size
            else None
        ),
        "median_frames_to_localised": float(np.median(frames)) if frames else None,
        "never_localised_rate": float(np.mean([f is None for f in first])) if first else None,
        "converged_share": float(np.mean(conv)) if conv.size else None,
        "confidently_wrong_rate": (
            float(np.mean(err[conv] > CONFIDENTLY_WRONG_M)) if conv.any() else None
        ),
        "stuck_wrong_rate": (
            stuck_episodes(list(zip(errors_m, converged, strict=True))) / len(errors_m)
            if errors_m
            else None
        ),
    }
    if confidence is not None and err.size:
        conf = np.concatenate([np.asarray(c, float) for c in confidence])
        out["reliability"] = reliability(conf, err)
    return out
