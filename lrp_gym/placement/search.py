"""Layout search: random layouts that satisfy the constraint, and an optimiser.

Both methods spend the same budget of ambiguity evaluations on the coarse search grid
(``placement.search_grid_m``) and then score their best ``refine_top`` layouts again on the
fine grid (``placement.grid_m``); the layout with the smallest fine ambiguous fraction wins.
The score is the whole ambiguous area fraction: for layouts that satisfy the constraint the
paper expects no systematic ambiguities, so this is the random ambiguous area, and with a
tolerance it also penalises layouts close to violating the constraint.

Feasible layouts keep every reflector's height, lie ``wall_distance_m`` from the walls and
outside obstacles (grown by the same distance), keep ``min_spacing_m`` between reflectors and
satisfy the constraint with margin ``constraint_tolerance_m`` (when the reflector counts allow
it: a type pair with fewer than two other reflectors always has systematic ambiguities).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from itertools import combinations

import numpy as np
from scipy.optimize import differential_evolution

from lrp_gym.config import ScenarioConfig
from lrp_gym.errors import InputError
from lrp_gym.placement.ambiguity import ambiguous_fraction
from lrp_gym.placement.grid import PositionGrid
from lrp_gym.placement.scenario import layout_arrays, tolerance_m
from lrp_gym.placement.symmetry import constraint_checks, constraint_margins, same_type_pairs
from lrp_gym.world import World
from lrp_gym.world.room import Room

Progress = Callable[[int, int], None]
#: Coarse scores of candidate layouts (k, M, 2) of a problem, in their order.
Scorer = Callable[["PlacementProblem", np.ndarray], np.ndarray]


@dataclass(frozen=True)
class PlacementProblem:
    """What a layout must satisfy and how it is scored.

    Attributes
    ----------
    room : Room
    heights_m : ndarray, shape (M,)
        Kept height of each reflector.
    type_index : ndarray of int, shape (M,)
    mount_height_m, tolerance_m, separation_m : float
        Radar height and the ambiguity definition (see :mod:`lrp_gym.placement.ambiguity`).
    min_spacing_m, wall_distance_m, constraint_tolerance_m : float
        Secondary requirements and the constraint's margin.
    search_grid, fine_grid : PositionGrid
        Coarse grid for the search, fine grid for the refinement.
    """

    room: Room
    heights_m: np.ndarray
    type_index: np.ndarray
    mount_height_m: float
    tolerance_m: float
    separation_m: float
    min_spacing_m: float
    wall_distance_m: float
    constraint_tolerance_m: float
    search_grid: PositionGrid
    fine_grid: PositionGrid
    use_constraint: bool = field(init=False)

    def __post_init__(self) -> None:
        t = np.asarray(self.type_index, dtype=int)
        inherent = any(len(t) - 2 < 2 for _ in same_type_pairs(t))
        object.__setattr__(self, "use_constraint", bool(constraint_checks(t)) and not inherent)

    @classmethod
    def from_config(
        cls, cfg: ScenarioConfig, grid_m: float | None = None, search_grid_m: float | None = None
    ) -> PlacementProblem:
        """The problem for a scenario's room, reflector heights and types, and placement."""
        world = World.from_config(cfg)
        pc = cfg.placement
        pos, idx, _ = layout_arrays(cfg)
        return cls(
            room=world.room,
            heights_m=pos[:, 2].copy(),
            type_index=idx,
            mount_height_m=cfg.radar.mount_height_m,
            tolerance_m=tolerance_m(cfg),
            separation_m=pc.separation_m,
            min_spacing_m=pc.min_spacing_m,
            wall_distance_m=pc.wall_distance_m,
            constraint_tolerance_m=pc.constraint_tolerance_m,
            search_grid=PositionGrid.from_room(
                world.room, search_grid_m or pc.search_grid_m, pc.clearance_m
            ),
            fine_grid=PositionGrid.from_room(world.room, grid_m or pc.grid_m, pc.clearance_m),
        )

    @property
    def n_reflectors(self) -> int:
        return len(self.type_index)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper x, y of a reflector (``wall_distance_m`` from the walls)."""
        lo = np.full(2, self.wall_distance_m)
        hi = self.room.size_m[:2] - self.wall_distance_m
        if np.any(hi <= lo):
            raise InputError("placement.wall_distance_m: leaves no room for the reflectors")
        return lo, hi

    def positions(self, xy_m: np.ndarray) -> np.ndarray:
        """Reflector positions (..., M, 3) from horizontal ones (..., M, 2) at the kept heights."""
        xy_m = np.asarray(xy_m, dtype=float)
        z = np.broadcast_to(self.heights_m, xy_m.shape[:-1])[..., None]
        return np.concatenate([xy_m, z], axis=-1)

    def violation(self, xy_m: np.ndarray) -> np.ndarray:
        """How far layouts (..., M, 2) are from feasible, in metres (0 = feasible)."""
        xy_m = np.asarray(xy_m, dtype=float)
        v = self._placement_violation(xy_m)
        if self.use_constraint:
            v = v + self._constraint_violation(xy_m)
        return v

    def feasible(self, xy_m: np.ndarray) -> np.ndarray:
        """``violation(xy_m) == 0`` for layouts (n, M, 2), as a mask (n,).

        The constraint (hundreds of checks with many same-type reflectors) is evaluated only
        on the layouts that pass the cheap walls, spacing and obstacle tests: in a room where
        hardly any layout is feasible, rejection sampling took minutes otherwise.
        """
        xy_m = np.asarray(xy_m, dtype=float)
        ok = self._placement_violation(xy_m) == 0.0
        if self.use_constraint and ok.any():
            ok[ok] = self._constraint_violation(xy_m[ok]) == 0.0
        return ok

    def _placement_violation(self, xy_m: np.ndarray) -> np.ndarray:
        """The walls, spacing and obstacle part of :meth:`violation`."""
        p = self.positions(xy_m)
        lo, hi = self.bounds()
        v = np.sum(np.maximum(lo - xy_m, 0) + np.maximum(xy_m - hi, 0), axis=(-1, -2))
        for i, j in combinations(range(self.n_reflectors), 2):
            gap = np.linalg.norm(p[..., i, :] - p[..., j, :], axis=-1)
            v = v + np.maximum(self.min_spacing_m - gap, 0.0)
        for box in self.room.obstacles:
            blo, bhi = box.min_m - self.wall_distance_m, box.max_m + self.wall_distance_m
            depth = np.min(np.minimum(p - blo, bhi - p), axis=-1)  # > 0 inside
            v = v + np.sum(np.maximum(depth, 0.0), axis=-1)
        return v

    def _constraint_violation(self, xy_m: np.ndarray) -> np.ndarray:
        """The constraint part of :meth:`violation` (only when ``use_constraint``)."""
        margin = constraint_margins(xy_m, self.type_index)
        return np.maximum(self.constraint_tolerance_m - margin, 0.0)

    def sample(self, rng: np.random.Generator, n: int, max_draws: int = 2_000_000) -> np.ndarray:
        """``n`` feasible layouts (n, M, 2), uniform in the bounds, by rejection (deterministic)."""
        lo, hi = self.bounds()
        out: list[np.ndarray] = []
        have, drawn = 0, 0
        batch = max(256, 4 * n)
        while have < n:
            if drawn >= max_draws:
                raise InputError(
                    f"placement: only {have} of {n} random layouts in {drawn} draws are feasible; "
                    "relax placement.min_spacing_m, wall_distance_m or constraint_tolerance_m"
                )
            xy = rng.uniform(lo, hi, size=(batch, self.n_reflectors, 2))
            drawn += batch
            ok = xy[self.feasible(xy)]
            out.append(ok[: n - have])
            have += len(out[-1])
        return np.concatenate(out)[:n]

    def score(self, xy_m: np.ndarray, fine: bool = False) -> float:
        """Ambiguous area fraction of one layout (M, 2) on the search or the fine grid."""
        return ambiguous_fraction(
            self.positions(xy_m),
            self.type_index,
            self.fine_grid if fine else self.search_grid,
            self.mount_height_m,
            self.tolerance_m,
            self.separation_m,
        )


@dataclass(frozen=True)
class SearchResult:
    """The chosen layout and how it was found.

    Attributes
    ----------
    method : str
        ``"random"`` or ``"optimize"``.
    positions_m : ndarray, shape (M, 3)
    score : float
        Ambiguous area fraction on the fine grid.
    coarse_score : float
        Its fraction on the search grid.
    evaluations : int
        Coarse ambiguity evaluations spent.
    refined : int
        Layouts scored on the fine grid.
    elapsed_s : float
        Wall time of the search, refinement included.
    coarse_scores : ndarray
        Every coarse score, in evaluation order.
    """

    method: str
    positions_m: np.ndarray
    score: float
    coarse_score: float
    evaluations: int
    refined: int
    elapsed_s: float
    coarse_scores: np.ndarray


def _refine(
    problem: PlacementProblem, layouts: np.ndarray, scores: np.ndarray, top: int
) -> tuple[int, float, int]:
    """Index of the best of the ``top`` coarse-best layouts on the fine grid, its score, count."""
    order = np.argsort(scores, kind="stable")[: max(1, min(top, len(scores)))]
    fine = np.array([problem.score(layouts[k], fine=True) for k in order])
    best = int(np.argmin(fine))
    return int(order[best]), float(fine[best]), len(order)


def random_search(
    problem: PlacementProblem,
    candidates: int,
    rng: np.random.Generator,
    refine_top: int = 8,
    progress: Progress | None = None,
    scorer: Scorer | None = None,
) -> SearchResult:
    """Best of ``candidates`` random feasible layouts (the paper's method).

    All layouts are drawn first, from ``rng``; ``scorer`` (default: ``problem.score`` on each,
    here) gives their coarse scores, e.g. in slices on a cluster: the same scores.
    """
    if candidates < 1:
        raise ValueError(f"candidates: must be at least 1, got {candidates}")
    start = time.perf_counter()
    layouts = problem.sample(rng, candidates)
    if scorer is not None:
        scores = np.asarray(scorer(problem, layouts), dtype=float)
    else:
        scores = np.empty(candidates)
        for k, xy in enumerate(layouts):
            scores[k] = problem.score(xy)
            if progress is not None:
                progress(k + 1, candidates)
    best, fine, refined = _refine(problem, layouts, scores, refine_top)
    return SearchResult(
        "random",
        problem.positions(layouts[best]),
        fine,
        float(scores[best]),
        candidates,
        refined,
        time.perf_counter() - start,
        scores,
    )


class _BudgetedObjective:
    """Differential evolution's objective on a budget of ``candidates`` grid evaluations.

    An infeasible layout scores ``1 + violation`` without a grid evaluation (so it does not use
    up the budget); a feasible one its coarse ambiguous fraction, recorded in ``seen`` and
    ``scores``; once the budget is spent every layout scores 2 and ``spent`` turns true.
    """

    def __init__(
        self, problem: PlacementProblem, candidates: int, progress: Progress | None
    ) -> None:
        self.problem = problem
        self.candidates = candidates
        self.progress = progress
        self.seen: list[np.ndarray] = []
        self.scores: list[float] = []

    @property
    def spent(self) -> bool:
        """True once ``candidates`` layouts have been evaluated."""
        return len(self.scores) >= self.candidates

    def __call__(self, x: np.ndarray) -> float:
        xy = x.reshape(self.problem.n_reflectors, 2)
        v = float(self.problem.violation(xy))
        if v > 0.0:
            return 1.0 + v
        if self.spent:
            return 2.0  # budget spent: the callback stops the run after this generation
        s = self.problem.score(xy)
        self.seen.append(xy.copy())
        self.scores.append(s)
        if self.progress is not None:
            self.progress(len(self.scores), self.candidates)
        return s


def optimise_search(
    problem: PlacementProblem,
    candidates: int,
    rng: np.random.Generator,
    refine_top: int = 8,
    progress: Progress | None = None,
) -> SearchResult:
    """Differential evolution on the same budget of ``candidates`` coarse evaluations.

    A small population (1.25 per coordinate, at least 8, the ``best1bin`` strategy) starts
    from random feasible layouts: on this rugged, noisy score many short generations beat a
    large population (measured in docs/placement.md); infeasible trial layouts score ``1 + violation`` without a grid evaluation (so they
    do not use up the budget), feasible ones their coarse ambiguous fraction. The run stops
    once the budget is spent; the best ``refine_top`` evaluated layouts are then refined.
    """
    if candidates < 1:
        raise ValueError(f"candidates: must be at least 1, got {candidates}")
    start = time.perf_counter()
    m = problem.n_reflectors
    pop = max(8, round(2.5 * m))
    init = problem.sample(rng, pop).reshape(pop, 2 * m)
    lo, hi = problem.bounds()
    bounds = list(zip(np.tile(lo, m), np.tile(hi, m), strict=True))
    objective = _BudgetedObjective(problem, candidates, progress)
    differential_evolution(
        objective,
        bounds,
        init=init,
        maxiter=100_000,
        tol=0.0,
        polish=False,
        rng=rng,
        callback=lambda *_a, **_k: objective.spent,
    )
    layouts = np.array(objective.seen)
    score_arr = np.array(objective.scores)
    best, fine, refined = _refine(problem, layouts, score_arr, refine_top)
    return SearchResult(
        "optimize",
        problem.positions(layouts[best]),
        fine,
        float(score_arr[best]),
        len(objective.scores),
        refined,
        time.perf_counter() - start,
        score_arr,
    )


def search_layout(
    problem: PlacementProblem,
    method: str,
    candidates: int,
    seed: int,
    refine_top: int = 8,
    progress: Progress | None = None,
    scorer: Scorer | None = None,
) -> SearchResult:
    """Run ``method`` (``"random"`` or ``"optimize"``) with a Generator seeded by ``seed``;
    ``scorer`` scores the random search's candidates (see :func:`random_search`)."""
    rng = np.random.default_rng(seed)
    if method == "random":
        return random_search(problem, candidates, rng, refine_top, progress, scorer)
    if scorer is not None:
        raise ValueError("scorer: only the random search scores its candidates independently")
    if method == "optimize":
        return optimise_search(problem, candidates, rng, refine_top, progress)
    raise ValueError(f"method: unknown {method!r}; choose random or optimize")
