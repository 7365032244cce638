"""Ground truth for scoring a run, one documented format per kind of input;
:func:`read_truth` tells them apart (the scorers are in :mod:`torchsym.runner.scoring`):

- **photos** (``image``): a text file of ``image x1 y1 x2 y2`` lines, one ground-truth
  axis per line (pixels, origin top-left; ``#`` starts a comment), the format of
  ``axes.txt`` of the ICCV 2017 symmetry challenge's photographs. Scored with the axis
  protocol under both criteria (thesis: 3 deg and 0.025 min(w, h); challenge: 10 deg and
  20 % of the ground-truth length, :func:`torchsym.metrics.evaluate_axes`).
- **point clouds** (``pointcloud``): a ``.jsonl`` file, one plane per line:
  ``{"input": "chair.ply", "normal": [nx, ny, nz], "offset": d}`` for the plane
  ``normal . x + offset = 0``, optionally with ``"box_min"`` and ``"box_max"`` (the
  object's bounding box; read from the input file when absent). Scored by plane
  precision, recall and F (Sec. 5.2.4, :func:`torchsym.metrics.evaluate_planes`).
- **meshes** (``mesh``): a folder of BCICP files, ``NAME.vts`` and ``NAME.sym.vts``
  (directly or under ``corres/``): line k of each is the 1-based vertex of the mesh at
  template landmark k and at its mirror landmark. Scored by the correspondence rate of
  each mesh's map at the landmarks and the mesh rate, the share of meshes above 75 %
  (Sec. 6.3.2, :func:`torchsym.metrics.correspondence_rate`, :func:`~torchsym.metrics.mesh_rate`).
- **superpixels** (``superpixels``, SymmSLIC's ``labels``): a folder of BSDS500
  ``NAME.mat`` files (``groundTruth/<split>``: several human segmentations each). Scored
  as D. Stutz's benchmark does (Sec. 4.4): boundary recall, undersegmentation error and
  achievable segmentation accuracy, the mean over the human segmentations and the best,
  and the superpixels produced (:mod:`torchsym.metrics.superpixels`).
- **object masks** (``segmentation``): a folder of ``NAME.png`` or ``NAME.bmp`` masks,
  the object non-zero; a GrabCut-style 128 band is unlabelled (neither error nor
  counted). SymmSLIC's ``mask`` is scored by the segmentation error over all pixels (the
  thesis's normalisation, Sec. 4.3.1) and over the mask's bounding box
  (:func:`torchsym.metrics.segmentation_error`); a symmetry map's ``score_map`` (the
  highest score over its axes, resized to the mask) by the SSM protocol of Sec. 3.3.3:
  ROC AUC, precision, recall and F_beta at 100/255 (:func:`torchsym.metrics.ssm_scores`).

A record is matched to its ground truth by the input's path, file name or stem, in that
order, else by the one ground-truth name that is its stem and a ``_`` suffix (the
Leeds Butterflies' ``NAME_seg0.png``). Inputs without ground truth are left out
(counted); inputs whose record is an error or a crash count as missed (no detection; a
correspondence rate of 0).
"""

from __future__ import annotations

import dataclasses
import functools
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import torch

from torchsym.errors import InputFileError

__all__ = ["GroundTruth", "MASK_SUFFIXES", "bsds_segmentations", "read_object_mask", "read_truth"]


@dataclasses.dataclass(frozen=True)
class GroundTruth:
    """Ground truth of one kind of input.

    Attributes:
        kind: ``"image"``, ``"pointcloud"``, ``"mesh"``, ``"superpixels"`` or ``"segmentation"``.
        items: per input name (path, file name or stem): for images a ``(G, 4)`` float64
            tensor of axes; for clouds ``{"normal" (3,), "offset" (), "box" (min, max) or
            None}``; for meshes ``(L, 2)`` int64 0-based landmark pairs; for superpixels
            and masks the ground-truth file (read when scored).
        source: the file or folder read.
    """

    kind: str
    items: dict[str, Any]
    source: str

    def find(self, input: str) -> Any | None:
        """The ground truth of ``input``, matched by path, file name, stem, then the one
        name that is the stem and a ``_`` suffix (``0010001_seg0`` for ``0010001.png``); or None."""
        p = Path(input)
        for name in (str(input), p.name, p.stem):
            if name in self.items:
                return self.items[name]
        prefixed = self._by_prefix.get(p.stem, [])
        return self.items[prefixed[0]] if len(prefixed) == 1 else None

    @functools.cached_property
    def _by_prefix(self) -> dict[str, list[str]]:
        """Names by each of their prefixes before a ``_`` (``a_b_c``: ``a``, ``a_b``)."""
        out: dict[str, list[str]] = {}
        for key in self.items:
            parts = key.split("_")
            for i in range(1, len(parts)):
                out.setdefault("_".join(parts[:i]), []).append(key)
        return out


def _read_axes_txt(path: Path) -> GroundTruth:
    items: dict[str, list[list[float]]] = {}
    for lineno, line in enumerate(path.read_text().splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split()
        try:
            if len(parts) != 5:
                raise ValueError
            coords = [float(v) for v in parts[1:]]
        except ValueError:
            raise InputFileError(f"truth: line {lineno} of {str(path)!r}: expected 'image x1 y1 x2 y2', got {line!r}") from None
        items.setdefault(parts[0], []).append(coords)
    return GroundTruth("image", {k: torch.tensor(v, dtype=torch.float64) for k, v in items.items()}, str(path))


def _vector(rec: Mapping[str, Any], name: str, where: str) -> torch.Tensor:
    try:
        t = torch.tensor(rec[name], dtype=torch.float64)
    except (KeyError, TypeError, ValueError):
        raise InputFileError(f"truth: {where}: expected {name!r} as a list of 3 numbers, got {rec.get(name)!r}") from None
    if t.shape != (3,):
        raise InputFileError(f"truth: {where}: expected {name!r} as a list of 3 numbers, got {rec.get(name)!r}")
    return t


def _read_planes(path: Path) -> GroundTruth:
    items: dict[str, Any] = {}
    for lineno, line in enumerate(path.read_text().splitlines(), 1):
        if not line.strip():
            continue
        where = f"line {lineno} of {str(path)!r}"
        try:
            rec = json.loads(line)
            offset = float(rec["offset"])
            name = str(rec["input"])
        except (json.JSONDecodeError, KeyError, TypeError, ValueError):
            raise InputFileError(f"truth: {where}: expected {{\"input\", \"normal\", \"offset\"}}, got {line[:80]!r}") from None
        box = (_vector(rec, "box_min", where), _vector(rec, "box_max", where)) if "box_min" in rec else None
        items[name] = {"normal": _vector(rec, "normal", where), "offset": torch.tensor(offset, dtype=torch.float64), "box": box}
    return GroundTruth("pointcloud", items, str(path))


def _read_vts(folder: Path) -> GroundTruth:
    items: dict[str, torch.Tensor] = {}
    for sym in sorted(list(folder.glob("*.sym.vts")) + list(folder.glob("corres/*.sym.vts"))):
        name = sym.name[: -len(".sym.vts")]
        base = sym.with_name(f"{name}.vts")
        if not base.is_file():
            raise InputFileError(f"truth: {str(sym)!r} has no {base.name!r} beside it")
        a, b = (np.loadtxt(f, dtype=np.int64, ndmin=1) for f in (base, sym))
        if a.shape != b.shape:
            raise InputFileError(f"truth: {base.name!r} and {sym.name!r} have {a.shape[0]} and {b.shape[0]} landmarks; expected as many")
        items[name] = torch.from_numpy(np.stack([a, b], axis=1) - 1)  # (L, 2), 0-based
    if not items:
        raise InputFileError(f"truth: folder {str(folder)!r} holds no NAME.vts / NAME.sym.vts pairs")
    return GroundTruth("mesh", items, str(folder))


MASK_SUFFIXES = (".png", ".bmp")


def _read_files(folder: Path, suffixes: tuple[str, ...], kind: str) -> GroundTruth:
    items = {f.stem: f for f in sorted(folder.iterdir()) if f.suffix.lower() in suffixes}
    return GroundTruth(kind, items, str(folder))


def read_truth(path: str | Path) -> GroundTruth:
    """Read a ground-truth file or folder in one of the formats of the module docstring.

    A folder is read as BCICP ``.vts`` files, else as BSDS500 ``.mat`` segmentations,
    else as ``.png``/``.bmp`` object masks; a ``.jsonl``/``.json`` file as planes, any
    other file as ``image x1 y1 x2 y2`` lines.

    Raises:
        InputFileError: missing, or not in the format its name announces (the line is named).
    """
    p = Path(path)
    if p.is_dir():
        if any(p.glob("*.vts")) or any(p.glob("corres/*.vts")):
            return _read_vts(p)
        if any(p.glob("*.mat")):
            return _read_files(p, (".mat",), "superpixels")
        if any(f.suffix.lower() in MASK_SUFFIXES for f in p.iterdir()):
            return _read_files(p, MASK_SUFFIXES, "segmentation")
        raise InputFileError(
            f"truth: folder {str(p)!r} holds no NAME.vts / NAME.sym.vts pairs, BSDS500 .mat files or .png/.bmp masks"
        )
    if not p.is_file():
        raise InputFileError(f"--truth: {str(p)!r} does not exist")
    if p.suffix.lower() in (".jsonl", ".json"):
        return _read_planes(p)
    return _read_axes_txt(p)


def bsds_segmentations(path: Path) -> list[np.ndarray]:
    import scipy.io

    try:
        gts = scipy.io.loadmat(str(path))["groundTruth"][0]
        return [np.asarray(g["Segmentation"][0, 0]) for g in gts]
    except (OSError, KeyError, IndexError, ValueError) as exc:
        raise InputFileError(f"truth: {str(path)!r} is not a BSDS500 groundTruth file ({exc})") from None


def read_object_mask(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """``(object, unlabelled)`` bool ``(H, W)`` of a mask file: non-zero is the object, a
    GrabCut-style 128 band is unlabelled."""
    import cv2

    m = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if m is None:
        raise InputFileError(f"truth: cannot read the mask {str(path)!r}")
    m = m[..., 0] if m.ndim == 3 else m
    return m > 128, m == 128
