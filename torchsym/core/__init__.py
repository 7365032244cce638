"""Pieces every solver shares: input checks, randomness, results, registry, configs."""

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
