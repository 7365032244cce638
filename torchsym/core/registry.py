"""A small registry of solvers by short name (after fvcore's).

A solver is a :class:`~torchsym.core.settings.Solver` (an ``nn.Module`` holding one
frozen :class:`~torchsym.core.settings.Settings` dataclass) whose ``forward`` takes the input (a point tensor, an image tensor, a mesh, or the
previous step's output) and returns a :class:`~torchsym.core.results.Result`.

    @register_solver("reflection_plane", kind="pointcloud", default=True)
    class ReflectionPlaneDetector(nn.Module): ...

``SOLVERS.get(name)`` fails with a message that lists every registered name. Config files
name solvers by these short names only, never by import path, so a config cannot run
arbitrary code and keeps working when a module moves.
"""

from __future__ import annotations

import dataclasses
import inspect
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Callable, TypeVar

from torchsym.errors import ConfigError

if TYPE_CHECKING:
    from torchsym.core.settings import Settings, Solver

__all__ = [
    "IMAGE_SUFFIXES", "INPUT_KINDS", "MESH_SUFFIXES", "PHOTO_SUFFIXES", "POINT_SUFFIXES", "USER_KINDS",
    "InputKind", "Registry", "SOLVERS", "SolverEntry", "register_solver",
]

#: file suffixes of images, of meshes, and of everything that holds points
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp", ".pgm", ".ppm")
MESH_SUFFIXES = (".ply", ".obj", ".off", ".stl")
POINT_SUFFIXES = MESH_SUFFIXES + (".xyz", ".npy", ".txt", ".pts")
#: photos COLMAP reads (the multi-view input)
PHOTO_SUFFIXES = (".jpg", ".jpeg", ".png", ".tif", ".tiff", ".bmp")


@dataclasses.dataclass(frozen=True)
class InputKind:
    """One kind of input a pipeline takes.

    Attributes:
        name: the kind's name in configs (``input:``), ``--kind`` and ``detect(kind=...)``.
        summary: what it is, with its shape.
        suffixes: the files that hold it (a folder's other files are skipped with a note).
        grouped: several files make one input (the photos of one scene): a folder, a
            list of paths or a glob is one input, and a folder of folders one per folder.
    """

    name: str
    summary: str
    suffixes: tuple[str, ...]
    grouped: bool = False


#: The kinds of input torchsym knows, in the one place every front door reads them from.
INPUT_KINDS: dict[str, InputKind] = {k.name: k for k in (
    InputKind("pointcloud", "a 3D point cloud, (N, 3) float; a mesh is sampled on its surface", POINT_SUFFIXES),
    InputKind("points", "a d-dimensional point set, (N, D) float, D >= 2", POINT_SUFFIXES),
    InputKind("image", "an image, (B, C, H, W) float in [0, 1]", IMAGE_SUFFIXES),
    InputKind("mesh", "a triangle mesh (torchsym.mesh.Mesh)", MESH_SUFFIXES),
    InputKind("multiview", "photos of one scene from several viewpoints (a folder, a list of paths or a glob)",
              PHOTO_SUFFIXES, grouped=True),
    InputKind("any", "the previous step's output", ()),
)}

#: the kinds a user may ask for (every kind but ``any``)
USER_KINDS: tuple[str, ...] = tuple(k for k in INPUT_KINDS if k != "any")

T = TypeVar("T")


@dataclasses.dataclass(frozen=True)
class SolverEntry:
    """One registered solver: its class, the input kind it takes and a one-line summary."""

    name: str
    cls: type
    kind: str
    summary: str

    @property
    def settings_class(self) -> type[Settings]:
        """The solver's :class:`~torchsym.core.settings.Settings` class."""
        return self.cls.settings_class

    def parameters(self) -> list[str]:
        """The names of the solver's top-level settings (groups by their own name)."""
        return self.settings_class.field_names()

    def defaults(self) -> dict[str, Any]:
        """The solver's default settings, nested as a YAML step's ``params``."""
        return self.settings_class().to_dict()

    def settings(self, params: Mapping[str, Any] | None = None, *, where: str = "") -> Settings:
        """The settings a YAML step's ``params`` give (checked; typos name the valid keys)."""
        try:
            return self.settings_class.from_dict(params or {}, where="params")
        except ConfigError as exc:
            raise ConfigError(f"{where}: solver {self.name!r}: {exc}" if where else f"solver {self.name!r}: {exc}") from None


class Registry:
    """Maps short names to solver classes, with one default solver per input kind."""

    def __init__(self, what: str) -> None:
        self.what = what
        self._entries: dict[str, SolverEntry] = {}
        self._defaults: dict[str, str] = {}
        self._loaded = False

    def _load(self) -> None:
        """Import every torchsym subpackage once, so that every solver is registered
        before the first lookup (the package imports its members on first use)."""
        if not self._loaded:
            self._loaded = True
            import torchsym

            torchsym.load_all()

    def register(self, name: str, *, kind: str, default: bool = False) -> Callable[[T], T]:
        """Decorator registering a class under ``name`` for inputs of ``kind``."""
        if kind not in INPUT_KINDS:
            raise ValueError(f"kind: expected one of {sorted(INPUT_KINDS)}, got {kind!r}")

        def deco(cls: T) -> T:
            from torchsym.core.settings import Settings, Solver

            if not (isinstance(cls, type) and issubclass(cls, Solver)) or cls.settings_class is Settings:
                raise TypeError(f"{name}: a registered solver must subclass Solver and set settings_class")
            if name in self._entries and self._entries[name].cls is not cls:
                raise ValueError(f"{self.what} {name!r} is already registered to {self._entries[name].cls.__name__}")
            doc = (inspect.getdoc(cls) or "").strip().splitlines()
            self._entries[name] = SolverEntry(name, cls, kind, doc[0] if doc else "")  # type: ignore[arg-type]
            if default:
                self._defaults[kind] = name
            return cls

        return deco

    def get(self, name: str) -> SolverEntry:
        """The entry named ``name``; :class:`ConfigError` listing the known names if none."""
        self._load()
        try:
            return self._entries[name]
        except KeyError:
            raise ConfigError(f"unknown {self.what} {name!r}; known: {', '.join(sorted(self._entries)) or 'none'}") from None

    def default_for(self, kind: str) -> SolverEntry:
        """The default solver for inputs of ``kind``."""
        self._load()
        if kind not in self._defaults:
            known = ", ".join(f"{k} -> {v}" for k, v in sorted(self._defaults.items()))
            raise ConfigError(f"no default {self.what} for input kind {kind!r}; defaults: {known or 'none'}")
        return self._entries[self._defaults[kind]]

    def names(self, kind: str | None = None) -> list[str]:
        """Registered names, optionally only those taking ``kind``."""
        self._load()
        return sorted(n for n, e in self._entries.items() if kind is None or e.kind == kind)

    def __contains__(self, name: object) -> bool:
        self._load()
        return name in self._entries

    def __iter__(self):
        self._load()
        return iter(self._entries.values())


SOLVERS = Registry("solver")


def register_solver(name: str, *, kind: str, default: bool = False) -> Callable[[T], T]:
    """Register a solver class in :data:`SOLVERS` (see :meth:`Registry.register`)."""
    return SOLVERS.register(name, kind=kind, default=default)
