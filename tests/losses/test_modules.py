import torch

from torchsym.losses import (
    OrthogonalityLoss,
    PRSNetSymmetryLoss,
    SymmetryDistanceLoss,
    closest_point_grid,
    occupancy_grid,
    orthogonality_loss,
    prsnet_symmetry_loss,
    symmetry_distance,
)


def test_modules_call_the_functions():
    g = torch.Generator().manual_seed(0)
    p = 0.3 * torch.rand(2, 30, 3, generator=g)
    n, b = torch.randn(2, 2, 3, generator=g), torch.zeros(2, 2)
    mod = SymmetryDistanceLoss(kind="robust", threshold=0.1)
    assert torch.equal(mod(p, n, b), symmetry_distance(p, n, b, kind="robust", threshold=0.1, reduction="mean"))
    assert "kind='robust'" in repr(mod)
    cp, occ = closest_point_grid(p, 8), occupancy_grid(p, 8)
    assert torch.equal(PRSNetSymmetryLoss()(p, n, b, cp, occ), prsnet_symmetry_loss(p, n, b, cp, occ))
    assert torch.equal(OrthogonalityLoss()(n), orthogonality_loss(n, reduction="mean"))
