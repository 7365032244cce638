"""Settings of the boundary-clique axis detector (thesis Sec. 2.3)."""

from __future__ import annotations

import dataclasses
from typing import Literal

from torchsym.core.settings import Settings, group, setting
from torchsym.errors import ConfigError
from torchsym.features.sift import SIFT_MIN_SIDE
from torchsym.image.batching import check_sides

__all__ = ["BoundaryCliquesSettings", "Cliques", "Edges", "Segments", "SiftCandidates"]


@dataclasses.dataclass(frozen=True)
class Edges(Settings):
    """Boundary curves (Sec. 2.3.1, :func:`~torchsym.image.boundary.boundary_curves`)."""

    detector: Literal["edge_drawing", "canny"] = setting(
        "edge_drawing", "edge_drawing: OpenCV contrib chains; canny: kornia Canny, junction removal, own linking"
    )
    sigma: float = setting(2.0, "Gaussian smoothing of the edges and of the tangent gradient", unit="px", low=0.0, low_open=True)
    low_threshold: float = setting(0.015, "Canny's low gradient threshold (detector canny)", low=0.0, low_open=True)
    high_threshold: float = setting(0.04, "Canny's high gradient threshold (detector canny)", low=0.0, low_open=True)


@dataclasses.dataclass(frozen=True)
class Segments(Settings):
    """Boundary samples and the segments around them (Sec. 2.3.1)."""

    length: float = setting(24.0, "q: arc length of boundary around each sample; also the least chord", unit="px",
                            low=0.0, low_open=True)
    n_samples: int = setting(9, "orientation samples per segment (the integral of Eq. 2.9)", low=2)
    stride: float = setting(1.5, "arc length between boundary samples", unit="px", low=0.0, low_open=True)
    tangents: Literal["gradient", "chain"] = setting(
        "gradient", "gradient: from the smoothed image gradient; chain: differentiating the smoothed chain"
    )
    smooth: float = setting(2.0, "Gaussian smoothing of the pixel chain", unit="px", low=0.0, low_open=True)
    max_samples: int = setting(2000, "the most boundary samples (the stride widened beyond; the pair search is "
                              "quadratic in them)", low=2)


@dataclasses.dataclass(frozen=True)
class Cliques(Settings):
    """Dominant cliques of the pair graph (Eq. 2.11)."""

    solver: Literal["matching", "highs"] = setting(
        "matching", "LP of Eq. 2.11: matching (exact half-integral optimum) or highs (scipy linprog)"
    )
    min_support: int = setting(3, "a clique with fewer pairs ends the search", low=2, high=10_000_000)
    gather_support: bool = setting(True, "every symmetric pair near a clique's axis joins its support")


@dataclasses.dataclass(frozen=True)
class SiftCandidates(Settings):
    """Axes of mirrored-SIFT pairs (Sec. 2.2.1) as further candidates (not in the thesis)."""

    enabled: bool | None = setting(None, "add them; null: with score gradient only (they need it)")
    weight: float = setting(0.5, "factor on their axes' scores", low=0.0, low_open=True)
    max_keypoints: int = setting(1000, "the most SIFT keypoints", low=1)
    min_support: int = setting(3, "the least pairs of a candidate (as cliques.min_support)", low=1, high=10_000_000)
    backend: Literal["kornia", "opencv"] = setting("opencv", "SIFT's implementation: opencv (CPU, fast) or kornia (any device)")


@dataclasses.dataclass(frozen=True)
class BoundaryCliquesSettings(Settings):
    """Settings of :func:`~torchsym.image.boundary_cliques.boundary_clique_axes`."""

    edges: Edges = group(Edges)
    segments: Segments = group(Segments)
    theta: float = setting(8.0, "threshold of Eq. 2.9 on a pair's and a graph edge's orientation mismatch (thesis 5)",
                           unit="deg", low=0.0, high=180.0, low_open=True)
    axis_distance: float = setting(0.02, "midpoint-to-axis tolerance of a graph edge", unit="x longer side",
                                   low=0.0, low_open=True)
    max_boundary_pairs: int = setting(800, "the most boundary pairs in the graph (a seeded random subset beyond)", low=2)
    max_axes: int = setting(5, "k: the most dominant cliques extracted", low=1)
    cliques: Cliques = group(Cliques)
    score: Literal["gradient", "photometric", "support"] = setting(
        "gradient", "gradient: mirrored gradients (evidence); photometric: mirror correlation x support; support: pairs"
    )
    grow_threshold: float | None = setting(
        0.3, "with score gradient: local symmetry above which a segment grows; null: the pairs' extent", low=-1.0, high=1.0
    )
    sift: SiftCandidates = group(SiftCandidates)
    max_side: int | None = setting(640, "longest side an image is detected at (a scaled copy beyond); null: full size",
                                   unit="px", low=SIFT_MIN_SIDE)
    min_side: int | None = setting(None, "longest side below which an image is detected on a scaled-up copy; null: "
                                   "native size", unit="px", low=SIFT_MIN_SIDE, high=8192)
    seed: int = setting(0, "seed of the random subset of boundary pairs", low=0)

    def check(self) -> None:
        check_sides(self.min_side, self.max_side)
        if self.sift.enabled and self.score != "gradient":
            raise ConfigError(
                f"sift.enabled: needs score='gradient' (its axes are ranked by their evidence), got score={self.score!r}"
            )

    @property
    def use_sift(self) -> bool:
        """Whether the SIFT candidates run (``sift.enabled``, or by default with ``score="gradient"``)."""
        return self.score == "gradient" if self.sift.enabled is None else self.sift.enabled
