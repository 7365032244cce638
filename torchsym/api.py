"""``torchsym.detect``: one call from any input to its symmetry, and :func:`prepare`, the
step every front door (``detect``, ``torchsym detect``, ``torchsym run``) shares: read the
input, tell its kind, choose the config and fit the input to the pipeline."""

from __future__ import annotations

import dataclasses
import logging
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import torch

from torchsym.core.checks import as_tensor, check_dense, check_finite, check_scale
from torchsym.core.config import PipelineConfig, build_pipeline, default_config, load_config
from torchsym.core.registry import INPUT_KINDS, MESH_SUFFIXES, USER_KINDS
from torchsym.core.results import Result
from torchsym.errors import ConfigError, InputShapeError, InputValueError
from torchsym.geometry.mesh import Mesh
from torchsym.io.inputs import Source, expand_inputs
from torchsym.io.objects import from_user_object
from torchsym.io.read import infer_kind, load_input

__all__ = ["Prepared", "detect", "prepare", "solve"]

logger = logging.getLogger(__name__)

#: a mesh whose largest connected component holds less than this share of its vertices is
#: a model of several parts, for the point-cloud pipeline (the intrinsic one keeps one part)
MIN_MAIN_PART = 0.9


@dataclasses.dataclass(frozen=True)
class Prepared:
    """An input ready for its pipeline.

    Attributes:
        kind: the kind the pipeline takes and ``data`` now is.
        data: the tensor, :class:`~torchsym.geometry.mesh.Mesh` or list of photo paths.
        config: the pipeline's config (the one given, or the default for the input).
        notes: what was decided on the way (files skipped, a mesh sampled, a pipeline chosen).
    """

    kind: str
    data: Any
    config: PipelineConfig
    notes: tuple[str, ...] = ()


def _is_paths(x: Any) -> bool:
    return isinstance(x, (str, Path)) or (
        isinstance(x, (list, tuple)) and len(x) > 0 and all(isinstance(v, (str, Path)) for v in x)
    )


def _several(input: Any) -> bool:
    """Whether ``input`` names several files: a list of paths, a folder or a glob."""
    paths = [input] if isinstance(input, (str, Path)) else list(input)
    return len(paths) > 1 or Path(paths[0]).is_dir() or not Path(paths[0]).exists()


def _source(input: Any, want: str | None) -> Source:
    """The one :class:`Source` that a path, folder, glob or list of paths names."""
    paths = [input] if isinstance(input, (str, Path)) else list(input)
    sources = expand_inputs(paths, want)
    if len(sources) != 1:
        names = ", ".join(s.name for s in sources[:3])
        raise InputValueError(
            f"input: expected one input, got {len(sources)} ({names}...); torchsym.run takes many"
        )
    return sources[0]


def _read(source: Source, want: str | None) -> tuple[str, Any]:
    """``(kind, data)`` of ``source``: a scene's photo paths, or the file read. A mesh file
    stays a mesh for a point pipeline (sampled on its surface by :func:`prepare`)."""
    if want is not None and INPUT_KINDS[want].grouped:
        return want, [Path(f) for f in source.files]
    path = source.files[0]
    if want in ("pointcloud", "points") and Path(path).suffix.lower() in MESH_SUFFIXES:
        want = None
    return load_input(path, kind=want)


def _intrinsic_refusal(mesh: Mesh) -> str | None:
    """Why the intrinsic pipeline cannot take ``mesh`` (non-manifold edges, degenerate
    triangles, several parts), or None."""
    from torchsym.mesh.validate import validate_mesh

    try:
        checked = validate_mesh(mesh, components="largest")
    except InputValueError as exc:
        return str(exc)
    if checked.dropped_vertices > (1 - MIN_MAIN_PART) * checked.num_input_vertices:
        share = 1 - checked.dropped_vertices / checked.num_input_vertices
        return f"mesh: {checked.num_components} connected parts, the largest with {share:.0%} of the vertices"
    return None


def _sample(mesh: Mesh, cfg: PipelineConfig) -> torch.Tensor:
    from torchsym.geometry.sampling import sample_surface

    return sample_surface(mesh, cfg.surface.points, generator=cfg.surface.seed)


def prepare(
    input: Any,
    config: str | Path | Mapping[str, Any] | PipelineConfig | None = None,
    *,
    kind: str | None = None,
    overrides: Mapping[str, Any] | None = None,
) -> Prepared:
    """Read ``input`` if it names files, tell its kind, choose the config, fit the input.

    - A folder, a list of paths or a glob is one input of a grouped kind (``multiview``:
      the photos of one scene; files that are not photos skipped with a note).
    - A mesh given to a point pipeline (``input: pointcloud`` or ``points``) is sampled on
      its surface (``surface: {points, seed}`` of the config; default 20,000 points).
    - With neither ``config`` nor ``kind``, a mesh the intrinsic pipeline cannot take
      (non-manifold, degenerate triangles, several parts) gets the point-cloud pipeline,
      with a note.

    ``overrides`` (checked) apply to the chosen config: its last solver's settings, and
    ``surface.points`` / ``surface.seed``. Tensors and arrays are checked here (dense,
    real, finite, no stray coordinate) and detached: ``detect`` does not carry gradients.

    Raises:
        InputValueError: an unknown ``kind``; a path naming several inputs.
        ConfigError: a config for another kind of input.
    """
    if kind is not None and kind not in USER_KINDS:
        raise InputValueError(f"kind: expected one of {', '.join(USER_KINDS)} or None, got {kind!r}")
    cfg = None
    if config is not None:
        cfg = config if isinstance(config, PipelineConfig) else load_config(config)
    want = kind or (cfg.input if cfg is not None else None)
    notes: list[str] = []
    if isinstance(input, Source) or _is_paths(input):
        if want is None and not isinstance(input, Source) and _several(input):
            want = "multiview"  # several files are one input only as the photos of a scene
        source = input if isinstance(input, Source) else _source(input, want)
        notes += source.notes
        found, data = _read(source, want)
    elif want is not None and INPUT_KINDS[want].grouped:
        found, data = want, input  # tensors of a scene's photos, checked by the solver
    else:
        data = _in_memory(input)
        found = infer_kind(data)
        if found in ("pointcloud", "points"):
            check_scale(check_finite(as_tensor(data, "input"), "input"), "input")
    if cfg is None:
        problem = _intrinsic_refusal(data) if found == "mesh" and kind is None else None
        if problem is not None:
            notes.append(
                f"the intrinsic (mesh) pipeline cannot take this mesh ({problem}): the point-cloud pipeline runs on "
                "its surface instead (--kind mesh forces the mesh pipeline)"
            )
        cfg = default_config("pointcloud" if problem is not None else kind or found)
    cfg = cfg.with_overrides(dict(overrides or {}))
    if found == "mesh" and cfg.input in ("pointcloud", "points"):
        notes.append(
            f"sampled {cfg.surface.points} points by area on the surface of the mesh "
            f"({data.num_faces} triangles, {data.num_vertices} vertices; seed {cfg.surface.seed})"
        )
        data, found = _sample(data, cfg), "pointcloud"
    if found != cfg.input and not (found == "pointcloud" and cfg.input == "points"):
        raise ConfigError(f"config: pipeline {cfg.source!r} takes {cfg.input!r} input, but the input is a {found}")
    return Prepared(found, data, cfg, tuple(notes))


def _in_memory(x: Any) -> Any:
    """A tensor or array input as a dense, detached tensor of its own dtype (uint8 images
    stay uint8, so the image check scales them); the objects of trimesh, Open3D and PIL and
    ``(H, W, 3)`` photo arrays converted by :func:`~torchsym.io.objects.from_user_object`;
    other inputs unchanged."""
    x = from_user_object(x)
    if isinstance(x, np.ndarray):
        t = as_tensor(x, "input")
        return torch.from_numpy(np.ascontiguousarray(x)) if x.dtype in (np.uint8, np.uint16) else t
    if isinstance(x, torch.Tensor):
        return check_dense(x, "input").detach()
    return x


def solve(prepared: Prepared) -> Result:
    """Build ``prepared``'s pipeline and run it on its data."""
    return build_pipeline(prepared.config)(prepared.data)


def detect(
    input: Any,
    config: str | Path | Mapping[str, Any] | PipelineConfig | None = None,
    *,
    kind: str | None = None,
    **overrides: Any,
) -> Result:
    """Find the reflection symmetry of ``input`` with the pipeline its kind calls for.

    Args:
        input: a file path (point cloud, mesh or image); a folder, a list of photo paths
            or a glob (the photos of one scene, for ``multiview``); a tensor or array
            (``(N, 3)`` point cloud, ``(N, D)`` point set, ``(C, H, W)`` or
            ``(B, C, H, W)`` image, an ``(H, W, 3)`` uint8 photo as OpenCV and PIL give
            it, ``(V, C, H, W)`` photos with ``kind="multiview"``); a
            :class:`torchsym.mesh.Mesh`; or a ``trimesh.Trimesh`` / ``PointCloud``, an
            Open3D ``TriangleMesh`` / ``PointCloud`` or a ``PIL.Image``.
        config: a YAML path, a mapping, or a :class:`PipelineConfig`; None uses the
            default pipeline for the input's kind (:func:`prepare` says how a mesh
            is routed).
        kind: force the input kind (e.g. ``"pointcloud"`` to sample a mesh's surface,
            ``"multiview"`` for a folder or list of photos).
        **overrides: settings of the pipeline's last solver, checked against its
            signature (e.g. ``**{"init.n_samples": 800}``); ``surface.points`` and
            ``surface.seed`` set how a mesh is sampled.

    Raises:
        TorchsymError: a bad input, config or setting; a solver's refusal of a file's
            contents names the file.

    Returns:
        The solver's typed result (e.g. :class:`torchsym.ReflectionPlaneResult`).
        The notes of :func:`prepare` are logged as warnings.

    Example:
        >>> import torchsym
        >>> result = torchsym.detect(torchsym.data.sample_pointcloud())
        >>> result.score > 0.9
        True
    """
    try:
        prepared = prepare(input, config, kind=kind, overrides=overrides)
        for note in prepared.notes:
            logger.warning("%s: %s", _name(input), note)
        return solve(prepared)
    except (InputShapeError, InputValueError) as exc:  # say which file the solver refused
        if not _is_paths(input) or _name(input) in str(exc):
            raise
        raise type(exc)(f"input {_name(input)!r}: {exc}") from None


def _name(input: Any) -> str:
    if isinstance(input, (str, Path)):
        return str(input)
    if isinstance(input, Source):
        return input.name
    if _is_paths(input):
        return str(input[0]) + (f" and {len(input) - 1} more" if len(input) > 1 else "")
    return "input"

