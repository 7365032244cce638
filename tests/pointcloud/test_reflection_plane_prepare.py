"""torchsym.pointcloud.prepare: normalisation and samples."""

import pytest
import torch

from torchsym.errors import InputValueError
from torchsym.pointcloud.prepare import normalise


class TestNormalise:
    def test_smoke(self):
        x = torch.randn(100, 3, generator=torch.Generator().manual_seed(0), dtype=torch.float64) * 5 + 3
        n = normalise(x, torch.float32)
        diag = (n.xs.max(0).values - n.xs.min(0).values).norm()
        assert float(diag) == pytest.approx(1.0) and torch.allclose(n.xs * n.scale + n.origin, x)

    @pytest.mark.parametrize("factor", [2.0**700, 2.0**-700, 1e200])
    def test_extreme_scale_is_exact(self, factor):
        """A power-of-two rescale: normalised points of a scaled cloud equal the cloud's."""
        x = torch.randn(100, 3, generator=torch.Generator().manual_seed(1), dtype=torch.float64)
        a, b = normalise(x, torch.float64), normalise(x * factor, torch.float64)
        if factor != 1e200:
            assert torch.equal(a.xs, b.xs) and b.scale == a.scale * factor
        else:
            assert torch.allclose(a.xs, b.xs, rtol=0, atol=1e-12)

    def test_exception(self):
        with pytest.raises(InputValueError, match="points: expected a cloud spanning at least a plane, got 5 copies"):
            normalise(torch.ones(5, 3, dtype=torch.float64) * 1e300, torch.float64)
