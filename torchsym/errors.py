"""Error types raised by torchsym.

Every error the library raises on purpose derives from :class:`TorchsymError`, so a
caller can catch the whole family at once. Errors about the shape or value of an input
also derive from :class:`ValueError`, and errors about files from :class:`OSError`, so
callers that already catch the built-in types keep working. Messages name the argument,
what was expected and what arrived, e.g.
``points: expected (N, D) with D >= 2 and N >= 4, got (3, 2)``.
"""

from __future__ import annotations

__all__ = [
    "TorchsymError",
    "InputShapeError",
    "InputValueError",
    "InputFileError",
    "ConfigError",
    "SolverError",
]


class TorchsymError(Exception):
    """Base class of every error raised by torchsym."""


class InputShapeError(TorchsymError, ValueError):
    """An argument has the wrong number of dimensions, size or dtype."""


class InputValueError(TorchsymError, ValueError):
    """An argument has the right shape but an unusable value (NaN, empty, degenerate)."""


class InputFileError(TorchsymError, OSError):
    """A file does not exist, cannot be read, or does not hold what was expected."""


class ConfigError(TorchsymError, ValueError):
    """A configuration names an unknown solver or parameter, or holds a bad value."""


class SolverError(TorchsymError, RuntimeError):
    """A numerical step failed in a way the input did not announce (e.g. no convergence)."""
