import numpy as np
import torch

from torchsym.optim.convergence import remaining_factor


def test_remaining_factor():
    assert remaining_factor(torch.tensor([1.0, 0.0]), None) == 1.0
    # steps halving: the geometric tail is one more step's worth
    assert abs(remaining_factor(np.array([0.5, 0.0]), np.array([1.0, 0.0])) - 2.0) < 1e-12
    assert remaining_factor(torch.tensor([-1.0, 0.0]), torch.tensor([1.0, 0.0])) == 1.0  # reversal: no tail
    assert abs(remaining_factor(np.array([1.0, 0.0]), np.array([1.0, 0.0])) - 20.0) < 1e-9  # clipped at 0.95
    assert abs(remaining_factor(np.array([1.0, 0.0]), np.array([1.0, 0.0]), max_ratio=0.5) - 2.0) < 1e-12
