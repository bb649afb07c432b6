"""Reflector placement: fingerprints, ambiguity maps, the layout constraint and layout search."""

from lrp_gym.placement.ambiguity import (
    AmbiguityResult,
    ambiguous_fraction,
    ambiguous_pairs,
    ambiguous_pairs_bruteforce,
    analyse_layout,
)
from lrp_gym.placement.fingerprint import fingerprints, quantise, unique_fingerprints
from lrp_gym.placement.grid import PositionGrid
from lrp_gym.placement.scenario import analyse_scenario, two_type_config, with_layout
from lrp_gym.placement.search import (
    PlacementProblem,
    SearchResult,
    optimise_search,
    random_search,
    search_layout,
)
from lrp_gym.placement.symmetry import (
    ConstraintReport,
    check_constraint,
    constraint_margins,
    pair_images,
    same_type_pairs,
)

__all__ = [
    "AmbiguityResult",
    "ConstraintReport",
    "PlacementProblem",
    "PositionGrid",
    "SearchResult",
    "ambiguous_fraction",
    "ambiguous_pairs",
    "ambiguous_pairs_bruteforce",
    "analyse_layout",
    "analyse_scenario",
    "check_constraint",
    "constraint_margins",
    "fingerprints",
    "optimise_search",
    "pair_images",
    "quantise",
    "random_search",
    "same_type_pairs",
    "search_layout",
    "two_type_config",
    "unique_fingerprints",
    "with_layout",
]
