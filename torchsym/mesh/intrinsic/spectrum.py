"""Steps 2-3: Laplace-Beltrami eigenpairs (Sec. 6.2.3) and HKS feature points (Sec. 6.2.4).

The eigensolver (ARPACK, single-threaded) runs beside what needs no eigenpair: the edge
graph, 2-rings, areas, boundary and winding tests, and step 9's vertex sample for each seed
it may be drawn from (read ahead from a copy of the generator).
"""

from __future__ import annotations

import dataclasses
import math
import time
from functools import partial

import numpy as np
import torch

from torchsym.core import parallel
from torchsym.core.random import draw_seed
from torchsym.errors import InputValueError
from torchsym.mesh.geodesic import thin_points
from torchsym.mesh.hks import heat_kernel_signature, hks_feature_points, hks_times
from torchsym.mesh.intrinsic.sample import Sample, draw_sample, sign_sample
from torchsym.mesh.intrinsic.settings import IntrinsicSymmetrySettings
from torchsym.mesh.intrinsic.workspace import Plan
from torchsym.mesh.operators import (
    consistently_wound,
    edge_face_counts,
    edge_graph,
    laplacian_eigen,
    mass_matrix,
    ring_neighbourhood,
)
from torchsym.mesh.orientation import tangent_frames

__all__ = ["Features", "Spectrum", "compute_spectrum", "feature_points"]


@dataclasses.dataclass(frozen=True)
class Spectrum:
    """Step 2's eigenpairs and what was computed beside them.

    Attributes:
        big_evals: ``(K,)`` eigenvalues (``K = plan.n_big``). big: ``(V, K)`` eigenfunctions.
        evals, evecs: ``(k,)`` and ``(V, k)``, the first ``n_eigen`` (eigenvalues clipped at 0).
        graph: ``(V, V)`` edge graph. two_ring: ``(V, V)`` CSR of 2-rings. area: ``(V,)``
        lumped areas. has_boundary: boundary edges exist. wound: the faces are consistently
        wound (checked only when a later step needs it). frames: the orientation test's tangent
        frames (None unless ``wound``). samples: step 9's sample for each guessed seed.
        sign_samples: the sign hypotheses' samples by guessed seed. t_eigen, t_topology: seconds.
    """

    big_evals: np.ndarray
    big: np.ndarray
    evals: np.ndarray
    evecs: np.ndarray
    graph: object
    two_ring: object
    area: np.ndarray
    has_boundary: bool
    wound: bool
    frames: object
    samples: list[Sample]
    sign_samples: dict
    t_eigen: float
    t_topology: float


@dataclasses.dataclass(frozen=True)
class Features:
    """Step 3's HKS feature points ``points (d,)``, the dense HKS ``dense_desc (V, h)`` and theirs ``desc (d, h)``."""

    points: np.ndarray
    dense_desc: np.ndarray
    desc: np.ndarray
    seconds: float


def _eigen(v: np.ndarray, f: np.ndarray, n_big: int, gen: torch.Generator) -> tuple[np.ndarray, np.ndarray, float]:
    tic = time.perf_counter()
    return *laplacian_eigen(v, f, n_big, generator=gen), time.perf_counter() - tic  # (K,), (V', K)


def _topology(v: np.ndarray, f: np.ndarray, plan: Plan, settings: IntrinsicSymmetrySettings, guesses: list[int], sign_guesses: list[int]) -> tuple:
    """What needs no eigenpair, and step 9's samples for the guessed seeds."""
    tic = time.perf_counter()
    n = v.shape[0]
    graph = edge_graph(v, f)
    two_ring = ring_neighbourhood(f, n, rings=2)  # (V', V'), also step 12's neighbourhoods
    area = mass_matrix(v, f).diagonal()  # (V',)
    has_boundary = bool((edge_face_counts(f)[1] == 1).any())
    later = settings.refine.orientation_weight > 0 or plan.polish or plan.realign
    wound = bool(plan.refine_iters) and later and consistently_wound(f)
    frames = tangent_frames(v, f) if wound else None  # the orientation test's, the same for every sample
    t_topology = time.perf_counter() - tic
    max_search = settings.select.max_search_vertices
    samples = [draw_sample(g, v, f, plan.n_rows, max_search, plan.n_targets, two_ring, frames) for g in guesses]
    sign_samples = {g: sign_sample(n, np.random.default_rng(g), v, max_search) for g in sign_guesses}
    return graph, two_ring, area, has_boundary, wound, frames, t_topology, samples, sign_samples


def compute_spectrum(v: np.ndarray, f: np.ndarray, plan: Plan, settings: IntrinsicSymmetrySettings, gen: torch.Generator) -> Spectrum:
    """Step 2: the ``plan.n_big`` smallest eigenpairs of the cotangent Laplacian of ``v (V, 3)``, ``f (F, 3)``.

    Raises:
        InputValueError: the second eigenvalue is 0 (a disconnected surface).
    """
    # step 9's seed is the generator's draw after the eigensolver's and the sign
    # hypotheses' (one per pairing with pairs): each possible seed is read ahead from a copy
    ahead = torch.Generator(device=gen.device)
    ahead.set_state(gen.get_state())
    n_sign = len(plan.weights) if settings.signs.n_uncertain else 0
    guesses = [draw_seed(ahead) for _ in range(2 + n_sign)][1:]
    sign_guesses = guesses[: len(plan.weights)] if settings.signs.n_uncertain else []
    (big_evals, big, t_eigen), topology = parallel.run_branches(
        [partial(_eigen, v, f, plan.n_big, gen), partial(_topology, v, f, plan, settings, guesses, sign_guesses)]
    )
    graph, two_ring, area, has_boundary, wound, frames, t_topology, samples, sign_samples = topology
    evals, evecs = np.maximum(big_evals[: plan.n_eigen], 0.0), big[:, : plan.n_eigen]  # (k,), (V', k)
    if not evals[1] > 1e-9:
        raise InputValueError("mesh: expected a connected surface, got a second Laplacian eigenvalue of 0")
    return Spectrum(
        big_evals, big, evals, evecs, graph, two_ring, area, has_boundary, wound, frames, samples, sign_samples, t_eigen, t_topology
    )


def feature_points(spectrum: Spectrum, settings: IntrinsicSymmetrySettings) -> Features:
    """Step 3: local maxima over 2-rings of the HKS at ``t = 4 ln 10 / lambda_2``, thinned by
    ``features.radius`` and cut to ``features.max_features``; and the dense HKS at ``features.n_times`` scales."""
    tic = time.perf_counter()
    evals, evecs = spectrum.evals, spectrum.evecs
    t_h = 4.0 * math.log(10.0) / evals[1]
    hks_th = heat_kernel_signature(evals, evecs, np.array([t_h]))[:, 0]  # (V',)
    points = hks_feature_points(hks_th, spectrum.two_ring)  # (d,)
    points = thin_points(spectrum.graph, points, settings.features.radius)[: settings.features.max_features]  # (d,)
    dense_desc = heat_kernel_signature(evals, evecs, hks_times(evals, settings.features.n_times))  # (V', h)
    return Features(points, dense_desc, dense_desc[points], time.perf_counter() - tic)
