"""Seeded randomness. torchsym never touches the global random state.

Every stochastic function takes ``generator: torch.Generator | None``. The docstring
text used across the library is:

    generator: the source of randomness (``torch.Generator``); None uses a fresh
        generator seeded with 0, so the same call gives the same bits.
"""

from __future__ import annotations

import numpy as np
import torch

from torchsym.errors import InputValueError

__all__ = ["DEFAULT_SEED", "draw_seed", "make_generator", "numpy_rng", "random_subset"]

DEFAULT_SEED = 0


def make_generator(generator: torch.Generator | int | None = None) -> torch.Generator:
    """Return a CPU ``torch.Generator``: the one given, one seeded with an int, or seed 0."""
    if isinstance(generator, torch.Generator):
        return generator
    if generator is None:
        generator = DEFAULT_SEED
    if isinstance(generator, bool) or not isinstance(generator, (int, np.integer)):
        raise InputValueError(f"generator: expected a torch.Generator, an int seed or None, got {generator!r}")
    g = torch.Generator(device="cpu")
    g.manual_seed(int(generator))
    return g


def draw_seed(generator: torch.Generator | None) -> int:
    """A seed in ``[0, 2^62)`` drawn from ``generator`` (advancing it once)."""
    return int(torch.randint(0, 2**62, (1,), generator=make_generator(generator)).item())


def numpy_rng(generator: torch.Generator | None) -> np.random.Generator:
    """A NumPy generator whose seed is drawn from ``generator`` (advancing it once): ``default_rng(draw_seed(generator))``."""
    return np.random.default_rng(draw_seed(generator))


def random_subset(n: int, k: int, generator: torch.Generator | None = None) -> torch.Tensor:
    """``k`` distinct indices in ``[0, n)`` drawn uniformly, sorted; all of them if k >= n.

    Args:
        n: population size.
        k: number of indices wanted.
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        ``(min(k, n),)`` int64 indices.
    """
    if k >= n:
        return torch.arange(n)
    perm = torch.randperm(n, generator=make_generator(generator))
    return perm[:k].sort().values
