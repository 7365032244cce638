import math

import pytest
import torch

from torchsym.errors import InputValueError
from torchsym.geometry import sample_cone


class TestSampleCone:
    def test_band_and_unit(self):
        n = torch.tensor([[0.0, 0.0, 2.0], [1.0, 1.0, 0.0]], dtype=torch.float64)
        s = sample_cone(n, 500, 10.0, 30.0, generator=torch.Generator().manual_seed(0))
        assert s.shape == (2, 500, 3)
        assert torch.allclose(s.norm(dim=-1), torch.ones(2, 500, dtype=torch.float64))
        ang = torch.rad2deg(torch.acos((s * (n / n.norm(dim=-1, keepdim=True)).unsqueeze(1)).sum(-1).clamp(-1, 1)))
        assert ang.min() >= 10.0 - 1e-6 and ang.max() <= 30.0 + 1e-6
        # cos uniform in [cos 30, cos 10]: its mean is the midpoint
        c = torch.cos(torch.deg2rad(ang)).mean()
        assert abs(float(c) - 0.5 * (math.cos(math.radians(10)) + math.cos(math.radians(30)))) < 0.01

    def test_same_seed_same_bits(self):
        n = torch.randn(3, 4)
        a = sample_cone(n, 7, generator=torch.Generator().manual_seed(3))
        b = sample_cone(n, 7, generator=torch.Generator().manual_seed(3))
        assert torch.equal(a, b)

    def test_exception(self):
        with pytest.raises(InputValueError, match="min_angle, max_angle"):
            sample_cone(torch.ones(3), 2, 40.0, 30.0)
