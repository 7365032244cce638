"""``torchsym.detect``: one call from any input to its symmetry."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import numpy as np
import torch

from torchsym.core.checks import as_tensor, check_dense, check_finite, check_scale
from torchsym.core.config import PipelineConfig, build_pipeline, default_config, load_config
from torchsym.core.results import Result
from torchsym.errors import ConfigError, InputShapeError, InputValueError
from torchsym.io.read import infer_kind, load_input

KINDS = ("pointcloud", "points", "image", "mesh")

__all__ = ["detect", "prepare"]


def prepare(
    input: Any, config: str | Path | Mapping[str, Any] | PipelineConfig | None = None, *, kind: str | None = None
) -> tuple[str, Any, PipelineConfig]:
    """Load ``input`` if it is a path, tell its kind and choose the config.

    Returns ``(kind, data, config)``: the config is the one given, or the default
    pipeline for the input's kind. Tensors and arrays are checked here (dense, real,
    finite, no stray coordinate) and detached: ``detect`` does not carry gradients.
    """
    if kind is not None and kind not in KINDS:
        raise InputValueError(f"kind: expected one of {', '.join(KINDS)} or None, got {kind!r}")
    cfg = None
    if config is not None:
        cfg = config if isinstance(config, PipelineConfig) else load_config(config)
    want = kind or (cfg.input if cfg is not None else None)
    if isinstance(input, (str, Path)):
        found, data = load_input(input, kind=want)
    else:
        data = _in_memory(input)
        found = infer_kind(data)
        if found in ("pointcloud", "points"):
            check_scale(check_finite(as_tensor(data, "input"), "input"), "input")
    if cfg is None:
        cfg = default_config(kind or found)
    elif found != cfg.input and not (found == "pointcloud" and cfg.input == "points"):
        raise ConfigError(f"config: pipeline {cfg.source!r} takes {cfg.input!r} input, but the input is a {found}")
    return found, data, cfg


def _in_memory(x: Any) -> Any:
    """A tensor or array input as a dense, detached tensor of its own dtype (uint8 images
    stay uint8, so the image check scales them); other inputs unchanged."""
    if isinstance(x, np.ndarray):
        t = as_tensor(x, "input")
        return torch.from_numpy(np.ascontiguousarray(x)) if x.dtype in (np.uint8, np.uint16) else t
    if isinstance(x, torch.Tensor):
        return check_dense(x, "input").detach()
    return x


def detect(
    input: Any,
    config: str | Path | Mapping[str, Any] | PipelineConfig | None = None,
    *,
    kind: str | None = None,
    **overrides: Any,
) -> Result:
    """Find the reflection symmetry of ``input`` with the pipeline its kind calls for.

    Args:
        input: a file path (point cloud, mesh or image), a tensor or array (``(N, 3)``
            point cloud, ``(N, D)`` point set, ``(C, H, W)`` or ``(B, C, H, W)`` image), or
            a :class:`torchsym.mesh.Mesh`.
        config: a YAML path, a mapping, or a :class:`PipelineConfig`; None uses the
            default pipeline for the input's kind.
        kind: force the input kind (e.g. ``"pointcloud"`` to treat a mesh's vertices as
            a point cloud).
        **overrides: settings of the pipeline's last solver, checked against its
            signature (e.g. ``**{"init.n_samples": 800}``).

    Raises:
        TorchsymError: a bad input, config or setting; a solver's refusal of a file's
            contents names the file.

    Returns:
        The solver's typed result (e.g. :class:`torchsym.ReflectionPlaneResult`).

    Example:
        >>> import torchsym
        >>> result = torchsym.detect(torchsym.data.sample_pointcloud())
        >>> result.score > 0.9
        True
    """
    _, data, cfg = prepare(input, config, kind=kind)
    pipeline = build_pipeline(cfg, **overrides)
    if not isinstance(input, (str, Path)):
        return pipeline(data)
    try:
        return pipeline(data)
    except (InputShapeError, InputValueError) as exc:  # say which file the solver refused
        raise type(exc)(f"input {str(input)!r}: {exc}") from None
