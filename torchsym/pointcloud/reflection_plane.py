"""The global reflection plane of a 3D point cloud (thesis Sec. 5.2, Algorithms 5 and 6).

The thesis poses detection as ``min_{S, c, Pi} |S (P - c 1^T) + c 1^T - P Pi|_F^2`` over
reflections ``S`` (Eq. 5.3), initialises ``S`` from a coarse grid of rotation angles
scored on a 500-point sample (Algorithm 5), and alternates trimmed mutual
nearest-neighbour correspondences with closed-form updates of ``S`` and ``c``
(Algorithm 6) until the normal moves less than 0.001 degrees and ``c`` less than 0.001.

Three changes make it more accurate (the first two also faster); all are switchable and measured in
``benchmarks/bench_pointcloud.py``:

* **The update is a true reflection, fitted jointly with the offset.** Algorithm 6 takes
  ``S = V U^T`` from the SVD of the cross-covariance, the best orthogonal matrix with
  determinant -1. That set also holds rotoreflections, which are not reflections: a
  reflection is ``S = I - 2 n n^T``, symmetric. Restricting ``S`` so and minimising over
  the normal ``n`` and the offset ``b`` together gives the exact least-squares reflection
  for the current pairs: the smallest eigenvector of a 3x3 matrix
  (:func:`torchsym.geometry.plane_from_pairs`, Eq. 5.6 with the weighting that makes it
  the reflection residual). ``update="procrustes"`` keeps the thesis's step.
* **Several starts, on a sphere of normals, scored robustly.** Algorithm 5 keeps the one
  best cell of a 10 x 10 grid of ``(theta_x, theta_y)`` in 20-degree steps, scored by the
  Frobenius residual. On real shapes (chairs, cups, aircraft) the best coarse cell often
  lies in the basin of a wrong local minimum, and a few outliers rank cells badly. We
  score 100 near-uniform normals with bounded Welsch kernels of the residuals, narrow the
  best by a beam search, add the cloud's principal axes (for an exactly symmetric set the
  normal is one of them), align each start by robust point-to-plane Gauss-Newton on a
  subsample, and keep the one with the highest soft share of points that find a mirror.
  Starts are tried in rank order (PCA axes first) until one reaches the support a
  perfect symmetry would have (calibrated on points left out of the subsample, or on each
  point's nearest other point) or clearly dominates the others; when none was accepted
  (heavy outliers, missing parts), the starts tried are also run through a few steps of
  Algorithm 6 on the subsample, whose mutual, trimmed pairs still move a start where the
  point-to-plane steps stall.
  The winner is then run through Algorithm 6 on the whole cloud (mutual pairs, trimmed
  at the median residual of the mutual pairs, extrapolated steps, progress judged by the
  lower quartile of the residuals, the thesis's tolerances).
* **A kernel stage for perturbed clouds** (``kernel_stage``): when almost no point has an
  exact mirror and noise has thickened the surface, nearest-neighbour pairs fit the
  noise, and the plane is refined instead by maximising the kernel correlation of the
  cloud's dense part with its reflection (soft assignment over the ``k`` nearest
  points), from the polished plane, the principal axes, the best starts and the normals
  the kernel itself scores best.

``configs/pointcloud_plane_thesis.yaml`` turns these changes off as far as they are
switchable (see the settings below).

Nearest neighbours use scipy's cKDTree on the CPU and chunked ``cdist`` elsewhere
(:class:`torchsym.matching.KNNIndex`).
"""

from __future__ import annotations

import dataclasses
import logging
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from torchsym.core.checks import check_in_range, check_int, check_points, check_positive
from torchsym.core.random import make_generator, random_subset
from torchsym.core.registry import register_solver
from torchsym.core.results import Result
from torchsym.errors import InputValueError
from torchsym.geometry.reflection import (
    canonical_sign,
    reflect_points,
    reflection_matrix,
    reflection_transform,
    spread_normals,
)
from torchsym.matching.knn import KNNIndex, mutual_nearest
from torchsym.pointcloud.alignment import (
    alternate,
    kernel_refine,
    kernel_score,
    local_pca,
    pre_align,
    support,
    surface_variation,
)
from torchsym.pointcloud.candidates import (
    initial_normals,
    score_normals,
    sphere_normals,
)

log = logging.getLogger(__name__)

#: quantile of nearest-neighbour distances that sets the kernel widths of the search
SPACING_QUANTILE = 0.1
# The dense part of the subsample (_dense_part) gives the PCA axes and the scoring sample
# when at least SPARSE_MIN_SHARE of the points are farther than SPARSE_FACTOR spacings from
# any other. On the benchmark's 1,000-point clouds that share is at most 0.13 when clean,
# 0.03 under perturbation, and at least 0.17 (median 0.29) with 50 to 200 % outliers.
SPARSE_FACTOR = 6.0
SPARSE_MIN_SHARE = 0.15
# When no start is accepted after the pre-alignment, Algorithm 6 runs from each on the
# subsample for at most FALLBACK_ITER steps (to the pre-alignment's angle tolerance; the
# polish on the whole cloud does the rest), and the search stops once START_PATIENCE starts
# in a row have not raised the best support by 0.005.
FALLBACK_ITER = 10
START_PATIENCE = 5
# A start whose support is DOMINANCE times (and DOMINANCE_GAP above) the median support of
# at least DOMINANCE_AFTER tried starts ends the list of starts (see _dominant).
DOMINANCE = 1.5
DOMINANCE_GAP = 0.05
# The acceptance reference is at least this: with outliers most of a cloud, the reference
# is dominated by the outliers' own neighbour distances, which a wrong plane's reflected
# outliers reach as well (at 200 % outliers F fell from 0.88 to 0.82 without the floor).
REFERENCE_FLOOR = 0.5
DOMINANCE_AFTER = 6
# The kernel stage (after the polish) runs when fewer than KERNEL_TRIGGER of the points
# have a mirror within KERNEL_EXACT of the inlier tolerance and the surface is thickened
# (surface variation above KERNEL_VARIATION). A mirror-paired cloud (and its inliers
# among outliers: a third of the points at 200 % outliers) has such exact pairs, a
# perturbed cloud about 1 % (thesis 5.2.4's perturbation, w = 20 to 200, on the
# benchmark's clouds); a surface sampled independently on each side has none either, but
# is thin (variation 0.005 to 0.08 against 0.11 to 0.14 under that perturbation), and
# there the stage only cost time. The kernel is computed on the dense part of the
# subsample (_dense_part): uniform outliers in a box are symmetric about the box's planes,
# and on the whole cloud the kernel rewards those. Kernel width: KERNEL_WIDTH times the
# median nearest-neighbour residual of the dense part at the polished plane. Refined
# besides the polished plane and the principal axes: up to KERNEL_STARTS best-supported
# starts and the KERNEL_SCAN_STARTS best of Algorithm 5's normals by kernel score.
KERNEL_EXACT = 0.05
KERNEL_TRIGGER = 0.1
KERNEL_VARIATION = 0.1
KERNEL_WIDTH = 2.0
KERNEL_STARTS = 8
KERNEL_SCAN_STARTS = 4
KERNEL_POLISH_ITER = 100
# The kernel stage runs on the dense part of the subsample: points whose DENSE_K-th nearest
# neighbour is within DENSE_FACTOR times the DENSE_QUANTILE quantile of those distances
# (a local density at least 1 / DENSE_FACTOR^2 of that quantile point's on a surface,
# 1 / DENSE_FACTOR^3 in a volume). See _dense_part.
DENSE_K = 10
DENSE_QUANTILE = 0.2
DENSE_FACTOR = 2.0

__all__ = ["ReflectionPlaneDetector", "ReflectionPlaneResult", "detect_reflection_plane", "sphere_normals"]


@dataclasses.dataclass(frozen=True)
class ReflectionPlaneResult(Result):
    """The reflection plane of a point cloud.

    Attributes:
        normal: ``(3,)`` unit normal of the plane, largest-magnitude component positive.
        offset: ``()`` offset: the plane is ``normal . x + offset = 0``.
        matrix: ``(3, 3)`` the reflection's linear part ``I - 2 n n^T`` (the thesis's S).
        transform: ``(4, 4)`` homogeneous reflection acting on ``[x; 1]``.
        center: ``(3,)`` the thesis's ``c``: the centroid of the matched pairs' midpoints,
            a point on the plane.
        pairs: ``(M, 2)`` int64 index pairs ``(i, j)``, ``i <= j``, of mutual
            nearest-neighbour mirror points within the inlier tolerance (``i == j``: a
            point on the plane).
        inliers: ``(N,)`` bool, points whose mirror image lands within the tolerance of
            the cloud.
        residual: median distance from a point's mirror image to its nearest point,
            over all points, in input units. Like ``pairs`` and ``inliers`` it is
            measured with the plane of the last Algorithm 6 step, which differs from
            ``normal``/``offset`` by less than the tolerances (``tol_angle``, ``tol_offset``).
        score: share of points that are inliers, in [0, 1]: near 1 for a symmetric
            cloud, low when the cloud has no reflection symmetry.
        tolerance: the inlier distance used (``inlier_factor`` x the median spacing).
        iterations: alternation steps taken by the winning start (subsample + full).
        converged: whether the winning start met the angle and offset tolerances.
        n_starts: starts refined (fewer than offered when one reached ``accept``).
        timings: seconds per stage (``init``: normalisation, subsample, PCA axes;
            ``refine``: the starts on the subsample, including Algorithm 5's scoring of
            candidate normals when no PCA axis is accepted; ``polish``; ``total``).
    """

    normal: torch.Tensor
    offset: torch.Tensor
    matrix: torch.Tensor
    transform: torch.Tensor
    center: torch.Tensor
    pairs: torch.Tensor
    inliers: torch.Tensor
    residual: float
    score: float
    tolerance: float
    iterations: int
    converged: bool
    n_starts: int
    timings: dict[str, float]

    def reflect(self, points: torch.Tensor) -> torch.Tensor:
        """Reflect ``(..., N, 3)`` points through the detected plane."""
        return reflect_points(points, self.normal.to(points), self.offset.to(points))

    def write_artifacts(self, data: Any, out_dir: Path, stem: str) -> list[Path]:
        """A PLY of the cloud coloured by side with the plane as a quad and the pairs as
        edges, and a PNG of three views with the plane drawn."""
        from torchsym.viz.pointcloud import plot_reflection_plane, reflection_plane_ply

        out_dir = Path(out_dir)
        return [
            reflection_plane_ply(data, self, out_dir / f"{stem}_plane.ply"),
            plot_reflection_plane(data, self, out_dir / f"{stem}_plane.png"),
        ]


def _check_settings(**s: Any) -> dict[str, Any]:
    """Validate the detector's settings once, for the function and the module alike."""
    out = dict(s)
    for name in ("n_init_samples", "n_refine_samples", "n_polish_samples"):
        out[name] = check_int(s[name], name, minimum=4)
    for name in ("n_directions", "n_starts", "beam", "max_iter", "coarse_iter"):
        out[name] = check_int(s[name], name, minimum=1)
    out["grid_step"] = check_positive(s["grid_step"], "grid_step")
    out["inlier_factor"] = check_positive(s["inlier_factor"], "inlier_factor")
    for name in ("tol_angle", "tol_offset", "coarse_tol", "min_start_separation"):
        out[name] = check_positive(s[name], name, allow_zero=True)
    out["accept"] = check_in_range(s["accept"], "accept", 0.0, 1.0)
    if s["init"] not in ("sphere", "grid"):
        raise InputValueError(f"init: expected 'sphere' or 'grid', got {s['init']!r}")
    if s["update"] not in ("reflection", "procrustes"):
        raise InputValueError(f"update: expected 'reflection' or 'procrustes', got {s['update']!r}")
    for name in ("polish", "accelerate", "pca_starts", "coarse", "kernel_stage"):
        if not isinstance(s[name], bool):
            raise InputValueError(f"{name}: expected True or False, got {s[name]!r}")
    return out


def _dominant(supports: list[float]) -> bool:
    """True when, after at least ``DOMINANCE_AFTER`` starts, the best support is
    ``DOMINANCE`` times the median of all of them and ``DOMINANCE_GAP`` above it: a clear
    winner, though below the acceptance level (outliers have no mirror, so the true plane's
    support is about the share of inliers). No further start is tried; the Algorithm 6
    fallback still runs on the starts tried when none was accepted. On the benchmark's clouds with 50 % outliers this cut the time per
    cloud about 3x at the same F."""
    if len(supports) < DOMINANCE_AFTER:
        return False
    best, middle = max(supports), float(np.median(supports))
    return best >= DOMINANCE * middle and best - middle >= DOMINANCE_GAP


def _nn_probe(points: torch.Tensor, index: KNNIndex, gen: torch.Generator) -> torch.Tensor:
    """Distances from up to 1,000 random points to their nearest other point.

    Exact duplicates (distance 0, e.g. the shared vertices of a mesh's seams) say nothing
    about the sampling density and are left out, unless every probe is one.
    """
    probe = points[random_subset(points.shape[0], 1000, gen)]
    d, _ = index.query(probe, k=2)
    d = d[:, 1]
    positive = d[d > 0]
    return positive if positive.numel() else d


def _spacing(points: torch.Tensor, index: KNNIndex, gen: torch.Generator, q: float | tuple[float, ...] = 0.5):
    """Quantile ``q`` of the distance from a point to its nearest other point, on up to
    1,000 random points (a tuple of quantiles gives a tuple, from one query). A low
    quantile measures the densest part, the sampled surface, even when outliers (which
    are sparser) are most of the cloud."""
    d = _nn_probe(points, index, gen)
    if isinstance(q, tuple):
        return tuple(float(v) for v in d.quantile(torch.tensor(q, dtype=d.dtype, device=d.device)))
    return float(d.quantile(q))


def _dense_part(points: torch.Tensor, index: KNNIndex) -> tuple[torch.Tensor, KNNIndex]:
    """The points of the sampled surface with most scattered points left out, and their index.

    A point is kept when its ``DENSE_K``-th nearest neighbour is within ``DENSE_FACTOR``
    times the ``DENSE_QUANTILE`` quantile of those distances (over positive distances:
    stacks of exact duplicates would make it 0): outliers scattered through a volume are
    far sparser than a surface, even one thickened by noise. A point and its mirror image
    have the same neighbour distances on a symmetric shape, so the dense part of a
    symmetric cloud is symmetric up to its sampling. The kernel correlation is computed on
    it because uniform outliers in a box are symmetric about the box's own planes, and with
    the kernel's wide support their pairs outweigh the surface's (measured in
    ``kernel_stage``'s docstring). On a planted 1,000-point cloud at w = 20 with 200 %
    outliers it kept 995 to 1,000 of the surface points and 7 to 26 % of the outliers
    (6 seeds). The whole set is returned when every point passes or fewer than 4 would.
    The same dense part gives the PCA axes and the sample that scores the initial normals
    when many points are sparse (see :func:`detect_reflection_plane`); a rule on the
    nearest neighbour alone did that before, with the same F on the benchmark's outlier,
    missing-part and noise-plus-outlier protocols.
    """
    k = min(DENSE_K + 1, points.shape[0])
    dk = index.query(points, k=k)[0][:, -1]
    positive = dk[dk > 0]
    if positive.numel() == 0:
        return points, index
    keep = dk <= DENSE_FACTOR * float(positive.quantile(DENSE_QUANTILE))
    if int(keep.sum()) < 4 or bool(keep.all()):
        return points, index
    return points[keep], KNNIndex(points[keep])


def detect_reflection_plane(
    points: torch.Tensor,
    *,
    n_init_samples: int = 500,
    init: str = "sphere",
    n_directions: int = 100,
    grid_step: float = 20.0,
    n_starts: int = 40,
    beam: int = 8,
    min_start_separation: float = 10.0,
    n_refine_samples: int = 3000,
    n_polish_samples: int = 100000,
    update: str = "reflection",
    max_iter: int = 100,
    tol_angle: float = 1e-3,
    tol_offset: float = 1e-3,
    polish: bool = True,
    accelerate: bool = True,
    pca_starts: bool = True,
    coarse: bool = True,
    coarse_tol: float = 0.01,
    coarse_iter: int = 8,
    accept: float = 0.95,
    inlier_factor: float = 2.0,
    kernel_stage: bool = True,
    generator: torch.Generator | int | None = None,
) -> ReflectionPlaneResult:
    """Detect the global reflection plane of a 3D point cloud (thesis Sec. 5.2).

    Args:
        points: ``(N, 3)`` point cloud, N >= 4, not all on one line.
        n_init_samples: points sampled to score the initial normals (thesis: n2 = 500).
        init: ``"sphere"``: ``n_directions`` near-uniform normals on the half sphere;
            ``"grid"``: the thesis's (theta_x, theta_y) grid in ``grid_step`` degrees.
        n_directions: normals scored with ``init="sphere"``.
        grid_step: grid spacing in degrees with ``init="grid"`` (thesis: 20).
        n_starts: most well-separated initial normals refined, in rank order, until one is
            accepted (see ``accept``; thesis: 1). Under heavy outliers the starts ranked
            first often lie in a wrong basin although the true plane has the higher support,
            so more starts are tried there, and when none is accepted each is also run
            through a few steps of Algorithm 6 on the subsample (see ``FALLBACK_ITER``); a
            clean cloud accepts one of the first. With the fallback and the lower-quartile
            progress test of :func:`~torchsym.pointcloud.alignment.alternate`, on the
            benchmark's clouds F went from 0.62 to 0.88 at 200 % outliers and from 0.65 to
            0.74 with 28 % missing, at 0.4 s instead of 0.2 s per 3,000-point cloud.
        beam: normals kept in each round of the coarse-to-fine search (``init="sphere"``).
        min_start_separation: smallest angle in degrees between two starts.
        n_refine_samples: points used to refine each start before the final polish on
            the whole cloud; clouds this small or smaller are used whole.
        update: ``"reflection"``: exact least-squares reflection ``I - 2nn^T`` with its
            offset; ``"procrustes"``: the thesis's SVD step over det -1 matrices.
        max_iter: alternation steps per stage.
        tol_angle: stop when the normal moves less than this many degrees (thesis: 0.001).
        tol_offset: ... and the offset less than this fraction of the bounding-box
            diagonal (thesis: 0.001).
        n_polish_samples: points (a random subset, or all if fewer) on which Algorithm 6
            runs from the winning start to the thesis's tolerances. On a subsample the exact
            mirror points are mostly missing, which costs accuracy (about 0.01 degrees
            on 10,000 of 30,000 points against 1e-5 on all); correspondences and the
            score always use every point.
        polish: run that final stage (else the subsample's fit is returned, with
            correspondences from the whole cloud).
        accelerate: extrapolate steps while the progress residual falls (see :func:`alternate`);
            False is the thesis's plain alternation.
        pca_starts: also start from the three principal axes of the cloud, first (best
            scored first); when one is accepted, the candidate normals of Algorithm 5 are
            never scored, which halves the time on clean clouds.
        coarse: align every start by robust point-to-plane Gauss-Newton on the
            subsample (fast from far away); False runs Algorithm 6 there instead.
        coarse_tol: the pre-alignment stops when the normal moves less than this (degrees)...
        coarse_iter: ... or after this many steps (on a subsample it ends in a jitter of
            a few hundredths of a degree that the polish removes).
        accept: stop trying further starts once one's support reaches this share of the
            support a perfect symmetry would have on the subsample (starts are tried PCA
            axes first, then by initial cost). That reference is the support of points
            left out of the subsample against it (a mirror point is about as far from the
            subsample as any left-out point), or, when the subsample is the whole cloud, of
            each point's distance to its nearest other point.
        inlier_factor: a point is an inlier when its mirror image is within this many
            median point spacings of the cloud.
        kernel_stage: (an extension) after the polish, when fewer than 10 % of the points
            have an exact mirror (within 5 % of the inlier tolerance) and the cloud is no
            thin surface (:func:`~torchsym.pointcloud.alignment.surface_variation` above
            0.1; see ``KERNEL_TRIGGER``), refine the polished plane, the principal axes
            (with ``pca_starts``), up to 8 best-supported starts and the 4 best of
            ``n_directions`` sphere normals scored by the kernel itself, by maximising the
            kernel correlation of the cloud with its reflection
            (:func:`~torchsym.pointcloud.alignment.kernel_refine`, width twice the median
            nearest-neighbour residual), and keep the highest-scoring plane, refined to
            convergence. The kernel is computed on the subsample's dense part
            (:func:`_dense_part`), with most scattered outliers left out. Under the
            thesis's perturbation (Sec. 5.2.4) a point's mirror is rarely its
            reflection's nearest neighbour, and the nearest-neighbour pairs of Algorithm 6
            fit noise; the kernel weighs every neighbour. On the benchmark's clouds (F
            with every detection kept, 5 degrees; without the stage, then PCA + ICP, in
            brackets): 0.53 at w = 50 (0.18, 0.24), 0.09 at w = 100 (0, 0), 0.79 with
            isotropic noise at w = 50 (0.62, 0.59), and with w = 20 noise plus uniform
            outliers 1.00 at 50 % (0.76, 0.03) and 0.94 at 200 % (0.21, 0). At 200 %
            outliers without noise it ran on the 3 of 34 clouds where Algorithm 6 had
            ended on a wrong plane, which has no exact pairs, and found all 3 (F 0.91 to
            1.00); where Algorithm 6 found the plane, the inliers' exact pairs skip it.
            Computed on the whole subsample instead of its dense part, the kernel
            rewarded the outlier box's own planes (uniform outliers are symmetric about
            them): in a scratch run on the benchmark's clouds with other noise seeds, F at
            w = 20 with 200 % outliers fell from 0.18 to 0.09, and the dense part raised
            it to 0.79. Clean surfaces sampled independently on each side skip it (thin).
            A solid sampled through its volume runs it (no exact pairs, not thin): on a
            clean ellipsoid, 2 to 11x slower, within 1 degree with or without it. At
            w >= 150 at most 1 of 34 planes is within 5 degrees, for every method, and
            the figures are near chance (a random plane through the centre is within 45
            degrees of the truth on 29 % of clouds): the thesis's curve over thresholds
            gives 0.24 and 0.38 at w = 150 and 200 (PCA + ICP 0.15 and 0.24; the thesis
            reports 0.56 at 200), and 0.32 with isotropic noise at w = 200 (PCA + ICP
            0.35, one cloud more). The thesis's 0.56 was measured on upright models whose
            planes lie along the axes, where its perturbation keeps the symmetry exact:
            in that pose (each mesh cut by one of its own coordinate planes, unmoved) it
            gives 0.56 at w = 200 and 0.62 at w = 100 (without the stage 0.32 and 0.56;
            PCA + ICP 0.35 and 0.59). In a scratch run on the same clouds a kernel 0.5x
            to 4x this width raised no figure at w = 200 in either pose (0.27 to 0.38 in
            general pose, 0.38 to 0.53 in the thesis's) and lowered the thesis's curve
            at w = 50 to 0.71 to 0.79 from 0.82, though at 2x and 4x it raised the
            thesis's pose at w = 100 to 0.65 and 0.68. It costs about 0.33 to 0.4 s on a
            perturbed 1,000-point cloud, 1.4 s with 200 % outliers besides (benchmark
            medians per level; 0.45 to 0.6 and 1.7 s on an earlier, slower pass of this
            shared machine).
        generator: the source of randomness (``torch.Generator``); None uses a fresh
            generator seeded with 0, so the same call gives the same bits.

    Returns:
        :class:`ReflectionPlaneResult`.

    Raises:
        InputShapeError: ``points`` is not ``(N, 3)`` with N >= 4.
        InputValueError: NaN or infinite coordinates, or all points on one line.

    Example:
        >>> pts = torchsym.pointcloud.planted_symmetric_cloud(2000, generator=torch.Generator().manual_seed(0))
        >>> res = detect_reflection_plane(pts.points)
        >>> float(torchsym.geometry.plane_angle(res.normal, pts.normal)) < 1e-3
        True
    """
    t0 = time.perf_counter()
    pts = check_points(points, "points", dim=3, min_points=4)
    if not pts.is_floating_point() or pts.dtype in (torch.float16, torch.bfloat16):
        pts = pts.to(torch.float32)
    _check_settings(
        n_init_samples=n_init_samples, init=init, n_directions=n_directions, grid_step=grid_step, n_starts=n_starts,
        beam=beam, min_start_separation=min_start_separation, n_refine_samples=n_refine_samples,
        n_polish_samples=n_polish_samples, update=update, max_iter=max_iter, tol_angle=tol_angle,
        tol_offset=tol_offset, polish=polish, accelerate=accelerate, pca_starts=pca_starts, coarse=coarse,
        coarse_tol=coarse_tol, coarse_iter=coarse_iter, accept=accept, inlier_factor=inlier_factor,
        kernel_stage=kernel_stage,
    )
    gen = make_generator(generator)
    # float64 inside: float32 BLAS reductions can differ in the last bit between calls
    # (their blocking depends on memory alignment), which would break same-seed-same-bits.
    dtype = torch.float64
    x = pts.to(dtype)
    n = x.shape[0]

    # Normalise: centre at the median, unit bounding-box diagonal (undone at the end).
    lo, hi = x.min(0).values, x.max(0).values
    scale = float((hi - lo).norm())
    centered = x - x.mean(0)
    sv = torch.linalg.svdvals(centered.double())
    # the second singular value is at rounding level of the coordinates: one line
    if scale == 0:
        raise InputValueError(f"points: expected a cloud spanning at least a plane, got {n} copies of one point")
    if float(sv[1]) <= 1e3 * torch.finfo(pts.dtype).eps * float(sv[0]):
        raise InputValueError(f"points: expected a cloud spanning at least a plane, got {n} points on one line")
    origin = x.median(0).values
    xs = (x - origin) / scale  # (N, 3), diagonal 1

    # Algorithm 5: score candidate normals on a sample (see _initial_normals).
    sample = xs[random_subset(n, n_init_samples, gen)]  # (n2, 3)
    sub_idx = random_subset(n, n_refine_samples, gen) if n > n_refine_samples else None
    sub = xs[sub_idx] if sub_idx is not None else xs
    sub_index = KNNIndex(sub)
    probe_nn = _nn_probe(sub, sub_index, gen)
    spacing = float(probe_nn.quantile(SPACING_QUANTILE))
    # Dense part (_dense_part): a sampled surface is denser than scattered outliers, so when
    # a sizeable share of the points is sparse (outliers), the PCA axes and the sample that
    # scores candidate normals come from the dense part only; outliers otherwise dominate
    # both (uniform outliers in a box make the PCA axes the box's axes). On a symmetric
    # cloud the dense part is symmetric too (neighbour distances are invariant under the
    # reflection). Alternation still runs on every point of the subsample; the kernel stage
    # reuses the same dense part.
    dense: tuple[torch.Tensor, KNNIndex] | None = None
    sparse = float((probe_nn > SPARSE_FACTOR * spacing).double().mean())
    if spacing > 0 and sparse >= SPARSE_MIN_SHARE:
        dense = _dense_part(sub, sub_index)
        core_pts = dense[0]
        if int(core_pts.shape[0]) >= 4:
            sample = core_pts[random_subset(core_pts.shape[0], n_init_samples, gen)]
            centered = core_pts - core_pts.mean(0)
    pca: list[tuple[torch.Tensor, torch.Tensor]] = []
    if pca_starts:
        # For an exactly symmetric set the covariance commutes with the reflection, so the
        # plane's normal is one of its eigenvectors (the idea behind PCA-plane baselines).
        _, axes = torch.linalg.eigh(centered.T @ centered)
        axes = axes.T.to(dtype)  # (3, 3) one normal per row
        # tried best first by the narrow kernel of Algorithm 5's scoring (cheap: 3 planes)
        offs, (cost,) = score_normals(sample, sub_index, axes, (2.0 * spacing,))
        pca = [(axes[k], offs[k]) for k in cost.argsort().tolist()]

    def ranked_starts() -> list[tuple[torch.Tensor, torch.Tensor]]:
        """Algorithm 5's candidates, best first, at least min_start_separation apart.

        Scored only when no PCA axis was accepted: on clean clouds that is most of the
        time saved (the scoring is about half of a 30,000-point detection).
        """
        cand, b_cand, order = initial_normals(
            sample, sub_index, init=init, n_directions=n_directions, grid_step=grid_step, beam=beam,
            spacing=spacing, dtype=dtype,
        )
        return [(cand[k], b_cand[k]) for k in spread_normals(cand, order, n_starts, min_start_separation)]

    t_init = time.perf_counter()

    # Refine every start on the subsample; keep the one most points agree with.
    sub_tol = inlier_factor * spacing
    # The support a perfect symmetry would have: a point's mirror lies about as far from
    # the subsample as a point left out of it (or, when the subsample is the whole cloud,
    # as a point's nearest other point), so the same kernel over those distances.
    if sub_idx is not None:
        left = torch.ones(n, dtype=torch.bool, device=xs.device)
        left[sub_idx] = False
        left_idx = left.nonzero()[:, 0]
        d_ref, _ = sub_index.query(xs[left_idx[random_subset(left_idx.numel(), 1000, gen)]])
    else:
        d_ref = sub_index.query(sub[random_subset(n, 1000, gen)], k=2)[0][:, 1]
    reference = max(float(torch.exp(-0.5 * (d_ref / sub_tol) ** 2).mean()), REFERENCE_FLOOR)
    # local PCA once: the normals for the point-to-plane steps, the eigenvalues for the
    # kernel stage's thickness test
    sub_pca = local_pca(sub, sub_index) if coarse else None
    sub_normals = sub_pca[1][:, :, 0] if sub_pca is not None else None
    align_q = sub[random_subset(sub.shape[0], 1000, gen)] if sub.shape[0] > 1000 else sub
    best = None
    iters = 0
    tried = 0

    def run_alternate(nk, bk, limit=max_iter, tol=tol_angle):
        nk, bk, it_a, _, _, _, _ = alternate(
            sub, sub_index, nk, bk, update=update, max_iter=limit, tol_angle=tol, tol_offset=tol_offset,
            accelerate=accelerate,
        )
        return nk, bk, it_a

    aligned = []

    def try_starts(starts: list[tuple[torch.Tensor, torch.Tensor]]) -> bool:
        """Refine ``starts`` in order; True once one is accepted or dominates."""
        nonlocal best, iters, tried
        for nk, bk in starts:
            if coarse:
                raw = (nk, bk, *support(sub, sub_index, nk, bk, sub_tol))
                nk, bk, it_k = pre_align(
                    align_q, sub, sub_index, sub_normals, nk, bk, max_iter=coarse_iter, tol_angle=coarse_tol
                )
                frac, med = support(sub, sub_index, nk, bk, sub_tol)
                if (raw[2], -raw[3]) > (frac, -med):
                    # the point-to-plane steps made it worse: on an exactly symmetric cloud a
                    # principal axis is exact, and the steps on a subsample (without exact
                    # mirrors) jitter it by hundredths of a degree
                    nk, bk, frac, med = raw
            else:
                nk, bk, it_k = run_alternate(nk, bk)
                frac, med = support(sub, sub_index, nk, bk, sub_tol)
            aligned.append((frac, nk, bk, it_k))
            if best is None or (frac, -med) > (best[2], -best[3]):
                best = (nk, bk, frac, med)
                iters = it_k
            tried += 1
            if frac >= accept * reference or _dominant([a[0] for a in aligned]):
                return True
        return False

    if not try_starts(pca):
        try_starts(ranked_starts())
    if coarse and best[2] < accept * reference:
        # No start was accepted after the pre-alignment: run Algorithm 6 on the subsample
        # from each pre-aligned start, best supported first (see FALLBACK_ITER). Under heavy
        # outliers the point-to-plane steps barely move a start; the mutual, trimmed pairs
        # of Algorithm 6 still do.
        since = 0
        refined: list[float] = []
        for _, nk, bk, it_k in sorted(aligned, key=lambda a: -a[0]):
            nk, bk, it_a = run_alternate(nk, bk, FALLBACK_ITER, max(tol_angle, coarse_tol))
            frac, med = support(sub, sub_index, nk, bk, sub_tol)
            refined.append(frac)
            since = 0 if frac > best[2] + 0.005 else since + 1
            if (frac, -med) > (best[2], -best[3]):
                best = (nk, bk, frac, med)
                iters = it_k + it_a
            if frac >= accept * reference or since >= START_PATIENCE or _dominant(refined):
                break
    normal, offset = best[0], best[1]
    converged = False
    t_refine = time.perf_counter()

    # Algorithm 6 from the winner, to the thesis's tolerances, on up to n_polish_samples.
    final = None
    full_index = KNNIndex(xs) if sub is not xs else sub_index
    full_spacing = None
    if polish:
        if n > n_polish_samples:
            pol = xs[random_subset(n, n_polish_samples, gen)]
            pol_index = KNNIndex(pol)
            pol_spacing = _spacing(pol, pol_index, gen, q=SPACING_QUANTILE)
        else:
            pol, pol_index = xs, full_index
            pol_spacing, full_spacing = _spacing(xs, full_index, gen, q=(SPACING_QUANTILE, 0.5))
        normal, offset, it2, converged, _, pdist, pnn = alternate(
            pol, pol_index, normal, offset, update=update, max_iter=max_iter, tol_angle=tol_angle, tol_offset=tol_offset,
            accelerate=accelerate, max_residual=inlier_factor * pol_spacing,
        )
        iters += it2
        if pol is xs and pdist is not None:
            final = (pdist, pnn)
    if final is None:
        final = full_index.query(reflect_points(xs, normal, offset))
    dist, nn_idx = final
    if full_spacing is None:
        full_spacing = _spacing(xs, full_index, gen)
    tol = inlier_factor * max(full_spacing, 1e-12)
    t_kernel = 0.0
    if (
        kernel_stage
        and float((dist < KERNEL_EXACT * tol).double().mean()) < KERNEL_TRIGGER
        and surface_variation(sub, sub_index, eigenvalues=None if sub_pca is None else sub_pca[0]) > KERNEL_VARIATION
    ):
        # No exact mirror pairs and a surface thickened by noise. Nearest neighbours then
        # pair each point with an arbitrary neighbour of its noisy mirror; the kernel
        # correlation weighs them all (see KERNEL_TRIGGER).
        t_kernel = time.perf_counter()
        kpts, kindex = dense if dense is not None else _dense_part(sub, sub_index)
        width = KERNEL_WIDTH * float(kindex.query(reflect_points(kpts, normal, offset))[0].median())
        if width > 0:
            ranked = [(nk, bk) for _, nk, bk, _ in sorted(aligned, key=lambda a: -a[0])[:KERNEL_STARTS]]
            # Algorithm 5's normals scored by the kernel itself, planes through the dense
            # part's centroid (a symmetric set's centroid lies on its plane): the starts
            # above were ranked by nearest-neighbour support, which under noise can miss
            # the kernel maximum's basin.
            centroid = kpts.mean(0)
            cand = sphere_normals(n_directions, dtype=kpts.dtype).to(kpts.device)
            values = kernel_score(kpts, kindex, cand, -(cand @ centroid), width)  # (n_directions,)
            best = spread_normals(cand, values.argsort(descending=True), KERNEL_SCAN_STARTS, min_start_separation)
            scan = [(cand[j], -(cand[j] @ centroid)) for j in best]
            chosen = None
            for nk, bk in [(normal, offset), *pca, *ranked, *scan]:
                nk, bk, _ = kernel_refine(kpts, kindex, nk, bk, width)
                value = kernel_score(kpts, kindex, nk, bk, width)
                if chosen is None or value > chosen[0]:
                    chosen = (value, nk, bk)
            # the soft assignment converges slowly (about 50 steps from 8 degrees away): the
            # winner only is followed to convergence
            normal, offset, _ = kernel_refine(kpts, kindex, chosen[1], chosen[2], width, max_iter=KERNEL_POLISH_ITER)
            dist, nn_idx = full_index.query(reflect_points(xs, normal, offset))
        t_kernel = time.perf_counter() - t_kernel
    inliers = dist <= tol
    mutual = mutual_nearest(nn_idx, nn_idx)
    idx = torch.arange(n, device=nn_idx.device)
    good = inliers & mutual & (idx <= nn_idx)
    pairs = torch.stack([idx[good], nn_idx[good]], dim=1)
    keep = mutual & inliers
    mids = 0.5 * (xs[keep] + xs[nn_idx[keep]]) if bool(keep.any()) else xs
    center_s = mids.mean(0)
    center_s = center_s - ((center_s @ normal) + offset) * normal  # project onto the plane
    t_end = time.perf_counter()

    log.info(
        "reflection plane: %d points, %d starts, %d steps, converged %s, init %.3f s, refine %.3f s, polish %.3f s",
        n, tried, iters, converged, t_init - t0, t_refine - t_init, t_end - t_refine,
    )
    # One sign for every plane: the largest-magnitude component of the normal positive.
    normal, offset = canonical_sign(normal, offset)
    # Undo the normalisation: x = scale * xs + origin.
    out_dtype = pts.dtype
    normal_o = normal.to(out_dtype)
    offset_o = (offset * scale - (normal * origin).sum()).to(out_dtype)
    center_o = (center_s * scale + origin).to(out_dtype)
    return ReflectionPlaneResult(
        normal=normal_o,
        offset=offset_o,
        matrix=reflection_matrix(normal_o),
        transform=reflection_transform(normal_o, offset_o),
        center=center_o,
        pairs=pairs,
        inliers=inliers,
        residual=float(dist.median()) * scale,
        score=float(inliers.float().mean()),
        tolerance=tol * scale,
        iterations=int(iters),
        converged=bool(converged),
        n_starts=tried,
        timings={
            "init": t_init - t0,
            "refine": t_refine - t_init,
            "polish": t_end - t_refine - t_kernel,
            "kernel": t_kernel,
            "total": t_end - t0,
        },
    )


@register_solver("reflection_plane", kind="pointcloud", default=True)
class ReflectionPlaneDetector(nn.Module):
    """Global reflection plane of a 3D point cloud (thesis Sec. 5.2); see :func:`detect_reflection_plane`.

    The module stores the settings (validated once, here) and a seed; every call starts
    a fresh generator from that seed, so calling it twice gives the same bits.
    """

    def __init__(
        self,
        *,
        n_init_samples: int = 500,
        init: str = "sphere",
        n_directions: int = 100,
        grid_step: float = 20.0,
        n_starts: int = 40,
        beam: int = 8,
        min_start_separation: float = 10.0,
        n_refine_samples: int = 3000,
        n_polish_samples: int = 100000,
        update: str = "reflection",
        max_iter: int = 100,
        tol_angle: float = 1e-3,
        tol_offset: float = 1e-3,
        polish: bool = True,
        accelerate: bool = True,
        pca_starts: bool = True,
        coarse: bool = True,
        coarse_tol: float = 0.01,
        coarse_iter: int = 8,
        accept: float = 0.95,
        inlier_factor: float = 2.0,
        kernel_stage: bool = True,
        seed: int = 0,
    ) -> None:
        super().__init__()
        self.settings = _check_settings(
            n_init_samples=n_init_samples, init=init, n_directions=n_directions, grid_step=grid_step,
            n_starts=n_starts, beam=beam, min_start_separation=min_start_separation,
            n_refine_samples=n_refine_samples, n_polish_samples=n_polish_samples, update=update, max_iter=max_iter,
            tol_angle=tol_angle, tol_offset=tol_offset, polish=polish, accelerate=accelerate, pca_starts=pca_starts,
            coarse=coarse, coarse_tol=coarse_tol, coarse_iter=coarse_iter, accept=accept, inlier_factor=inlier_factor,
            kernel_stage=kernel_stage,
        )
        self.seed = check_int(seed, "seed", minimum=0)

    def forward(self, points: torch.Tensor, generator: torch.Generator | None = None) -> ReflectionPlaneResult:
        gen = generator if generator is not None else make_generator(self.seed)
        return detect_reflection_plane(points, generator=gen, **self.settings)

    def extra_repr(self) -> str:
        return ", ".join(f"{k}={v!r}" for k, v in self.settings.items()) + f", seed={self.seed}"
