"""Pieces every solver shares: input checks, randomness, results, registry, configs."""

from typing import TYPE_CHECKING

from torchsym._lazy import lazy_members

_EXPORTS: dict[str, str] = {
    **dict.fromkeys(("as_tensor", "check_finite", "check_image", "check_in_range", "check_int", "check_points",
                     "check_positive"), "torchsym.core.checks"),
    **dict.fromkeys(("make_generator", "numpy_rng", "random_subset"), "torchsym.core.random"),
    **dict.fromkeys(("SOLVERS", "Registry", "register_solver"), "torchsym.core.registry"),
    "Result": "torchsym.core.results",
}

__all__ = [
    "SOLVERS",
    "Registry",
    "Result",
    "as_tensor",
    "check_finite",
    "check_image",
    "check_in_range",
    "check_int",
    "check_points",
    "check_positive",
    "make_generator",
    "numpy_rng",
    "random_subset",
    "register_solver",
]

__getattr__, __dir__ = lazy_members(__name__, _EXPORTS, globals())

if TYPE_CHECKING:
    from torchsym.core.checks import (
        as_tensor,
        check_finite,
        check_image,
        check_in_range,
        check_int,
        check_points,
        check_positive,
    )
    from torchsym.core.random import make_generator, numpy_rng, random_subset
    from torchsym.core.registry import SOLVERS, Registry, register_solver
    from torchsym.core.results import Result
