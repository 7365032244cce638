"""The result of the intrinsic-symmetry method."""

from __future__ import annotations

import copy
import dataclasses
import threading
from typing import Any

import torch

from torchsym.core.results import Result

__all__ = ["Deferred", "IntrinsicSymmetryResult"]


def _same(value: Any) -> Any:
    return value


class Deferred:
    """A value computed on first use (once, whichever thread asks first), then kept.

    Pickled and deep-copied as its value.
    """

    def __init__(self, compute):
        self._compute, self._value, self._lock = compute, None, threading.Lock()

    def value(self) -> Any:
        with self._lock:
            if self._compute is not None:
                self._value, self._compute = self._compute(), None
            return self._value

    def __reduce__(self) -> tuple:
        return _same, (self.value(),)

    def __deepcopy__(self, memo: dict) -> Any:
        return copy.deepcopy(self.value(), memo)

    def __repr__(self) -> str:
        return "<searched when first read>" if self._compute is not None else repr(self._value)


@dataclasses.dataclass(frozen=True)
class IntrinsicSymmetryResult(Result):
    """The intrinsic reflection symmetry of a mesh (thesis Ch. 6).

    Attributes:
        map: ``(V,)`` int64, the intrinsically symmetric vertex of every input vertex
            (input order); ``-1`` for vertices of dropped components.
        functional_map: ``(k, k)`` ``C`` of the chosen hypothesis in ``k = n_eigen``
            eigenfunctions: ``diag(s)`` in the corrected basis ``Phi R`` for the pairings,
            the full ``C`` in ``Phi`` for the orientation and extrinsic hypotheses.
        rotation: ``(k, k)`` the correction ``R`` in SO(k) (identity when off).
        map_before_refine: ``(V,)`` int64, the thesis's dense map (Sec. 6.2.7) of the
            chosen hypothesis before ZoomOut (``map`` when refinement is off). Where ZoomOut's
            map replaced it, searched approximately when first read (outside ``timings``).
        refined_functional_map: ``(k_r, k_r)`` ``C`` of the last ZoomOut round in the first
            ``k_r`` eigenfunctions (``polish.n_eigen`` or ``refine.n_eigen``); ``(0, 0)``
            without refinement.
        eigenvalues: ``(k,)`` Laplace-Beltrami eigenvalues of the mesh scaled to unit area.
        pairs: ``(P, 2)`` int64 sparse pairs of symmetric feature points (input indices).
        feature_points: ``(d,)`` int64 HKS feature points (input indices).
        timings: seconds per stage and ``total``; branches on threads each count their own time.
        num_components: connected components of the input mesh.
        dropped_vertices: input vertices outside the solved component.
        correction_converged: whether every trust-region run of the chosen hypothesis converged.
        hypothesis: ``"pairs"``, ``"hks_pairs"``, ``"orientation"``, ``"signs"`` or ``"extrinsic"``.
        score: how well ``map`` passes as an intrinsic reflection, in [0, 1]: ``(1 - d / d_0)_+``
            times the share of sampled vertices around which it reverses the orientation (times one
            less the share it leaves in place when the faces are not consistently wound), ``d`` its
            sampled geodesic distortion, ``d_0 = select.score_distortion``; below
            ``select.weak_score`` a note says the symmetry found is weak.
        holes_closed: holes covered by new triangles before the spectrum.
        notes: what the solver did that a caller should know.

    A mesh over ``coarse.max_vertices`` vertices is solved on a coarse copy: ``map``,
    ``map_before_refine``, ``pairs`` and ``feature_points`` are then carried to the input's
    vertices, while the functional maps, ``rotation`` and ``eigenvalues`` are the copy's.
    """

    map: torch.Tensor
    functional_map: torch.Tensor
    rotation: torch.Tensor
    map_before_refine: torch.Tensor | Deferred
    refined_functional_map: torch.Tensor
    eigenvalues: torch.Tensor
    pairs: torch.Tensor
    feature_points: torch.Tensor
    timings: dict[str, float]
    num_components: int
    dropped_vertices: int
    correction_converged: bool
    hypothesis: str = "pairs"
    holes_closed: int = 0
    score: float = 0.0
    notes: tuple[str, ...] = ()

    def __getattribute__(self, name: str) -> Any:
        value = object.__getattribute__(self, name)
        if name == "map_before_refine" and isinstance(value, Deferred):
            value = value.value()
            object.__setattr__(self, name, value)  # a plain tensor from now on
        return value
