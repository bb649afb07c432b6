"""95 % confidence intervals for the robustness matrix: Wilson for rates over independent
episodes, a seeded percentile bootstrap over episodes for everything pooled over steps.

Steps within one episode are correlated (the same filter, the same perturbation draw), so a
statistic pooled over steps -- an error percentile, the share of steps localised -- is
resampled by whole episodes (a cluster bootstrap): each resample draws episodes with
replacement and pools their steps again.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TypeVar

import numpy as np
from scipy.stats import norm

#: Confidence level of every interval in the matrix.
LEVEL = 0.95
#: Bootstrap resamples per interval (the percentile ends move by well under 1 % of the width).
N_RESAMPLES = 2000

T = TypeVar("T")


def wilson_interval(successes: int, trials: int, level: float = LEVEL) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion.

    Unlike the normal (Wald) interval it stays inside [0, 1] and does not collapse to a point
    at 0 or ``trials`` successes, which the robustness cells often hit (100 % success).

    Parameters
    ----------
    successes, trials : int
        ``0 <= successes <= trials``, ``trials >= 1``.
    level : float
        Confidence level in (0, 1).

    Returns
    -------
    (float, float)
        Lower and upper bound.
    """
    if trials < 1:
        raise ValueError(f"trials: must be at least 1, got {trials}")
    if not 0 <= successes <= trials:
        raise ValueError(f"successes: must be in [0, trials={trials}], got {successes}")
    if not 0.0 < level < 1.0:
        raise ValueError(f"level: must be in (0, 1), got {level}")
    z = float(norm.ppf(0.5 + level / 2.0))
    p = successes / trials
    z2n = z * z / trials
    centre = (p + z2n / 2.0) / (1.0 + z2n)
    half = z / (1.0 + z2n) * np.sqrt(p * (1.0 - p) / trials + z2n / (4.0 * trials))
    # Exact ends at 0 and n successes (the formula gives them up to rounding).
    lo = 0.0 if successes == 0 else max(0.0, centre - half)
    hi = 1.0 if successes == trials else min(1.0, centre + half)
    return float(lo), float(hi)


def bootstrap_interval(
    episodes: Sequence[T],
    statistic: Callable[[Sequence[T]], float | None],
    rng: np.random.Generator,
    n_resamples: int = N_RESAMPLES,
    level: float = LEVEL,
) -> tuple[float, float] | None:
    """Percentile bootstrap interval of ``statistic`` over resampled episodes.

    Parameters
    ----------
    episodes : sequence
        One item per episode (e.g. that episode's per-step errors); resampled with replacement.
    statistic : callable
        Maps a list of episode items to a number, or None when undefined for that resample
        (such resamples are skipped).
    rng : numpy.random.Generator
        The only source of randomness: the same seed gives the same interval.
    n_resamples : int
        Number of bootstrap resamples.
    level : float
        Confidence level in (0, 1).

    Returns
    -------
    (float, float) or None
        The ``(1 - level) / 2`` and ``(1 + level) / 2`` quantiles of the resampled statistic;
        None without episodes or when the statistic is undefined on every resample.
    """
    if n_resamples < 1:
        raise ValueError(f"n_resamples: must be at least 1, got {n_resamples}")
    if not 0.0 < level < 1.0:
        raise ValueError(f"level: must be in (0, 1), got {level}")
    n = len(episodes)
    if n == 0:
        return None
    idx = rng.integers(0, n, size=(n_resamples, n))
    values = [statistic([episodes[i] for i in row]) for row in idx]
    kept = np.asarray([v for v in values if v is not None], dtype=float)
    if kept.size == 0:
        return None
    lo, hi = np.quantile(kept, [(1.0 - level) / 2.0, (1.0 + level) / 2.0])
    return float(lo), float(hi)


def pooled_percentile(q: float) -> Callable[[Sequence[np.ndarray]], float | None]:
    """Statistic: the ``q``-th percentile of the steps of all episodes pooled."""

    def stat(episodes: Sequence[np.ndarray]) -> float | None:
        a = np.concatenate(episodes) if len(episodes) else np.zeros(0)
        return float(np.percentile(a, q)) if a.size else None

    return stat


def pooled_share(episodes: Sequence[np.ndarray]) -> float | None:
    """Statistic: share of True steps over all episodes pooled (per-episode boolean arrays)."""
    total = sum(len(e) for e in episodes)
    return float(sum(int(np.sum(e)) for e in episodes) / total) if total else None


def median_of(episodes: Sequence[float | None]) -> float | None:
    """Statistic: median of per-episode numbers, None entries (not observed) left out."""
    a = [v for v in episodes if v is not None]
    return float(np.median(a)) if a else None
