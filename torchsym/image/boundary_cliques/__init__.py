"""Reflection symmetry axes from boundary orientation and dominant cliques (thesis Sec. 2.3).

Steps: :mod:`~torchsym.image.boundary` (curves and segments, Sec. 2.3.1) -> :mod:`.pairs`
(symmetric boundary pairs, Eq. 2.9) -> :mod:`.graph` (pairs with one axis) ->
:mod:`.cliques` (dominant cliques, Eq. 2.11) -> the shared verification tail
(:mod:`~torchsym.image.verification`); the top function is in :mod:`.detect`.
"""

from torchsym.image.boundary_cliques.cliques import dominant_clique
from torchsym.image.boundary_cliques.detect import BoundaryCliqueDetector, boundary_clique_axes
from torchsym.image.boundary_cliques.pairs import symmetric_boundary_pairs
from torchsym.image.boundary_cliques.settings import BoundaryCliquesSettings, Cliques, Edges, Segments, SiftCandidates

__all__ = [
    "BoundaryCliqueDetector",
    "BoundaryCliquesSettings",
    "Cliques",
    "Edges",
    "Segments",
    "SiftCandidates",
    "boundary_clique_axes",
    "dominant_clique",
    "symmetric_boundary_pairs",
]
