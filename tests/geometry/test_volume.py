import pytest
import torch

from torchsym.errors import InputShapeError
from torchsym.geometry import grid_cell_centres, reflect_volume


def _sdf(shape, centre, radius=0.2):
    x = grid_cell_centres(shape, 0.5, dtype=torch.float64)
    return ((x - torch.tensor(centre, dtype=torch.float64)).norm(dim=-1) - radius)[None, None]


class TestReflectVolume:
    def test_cell_centres(self):
        c = grid_cell_centres((4,), 0.5)
        assert torch.allclose(c[:, 0], torch.tensor([-0.375, -0.125, 0.125, 0.375]))

    def test_axis_plane_is_flip(self):
        # plane x = 0 (first spatial axis): the reflection flips that axis exactly
        v = torch.randn(2, 3, 6, 5, 4, dtype=torch.float64)
        n = torch.tensor([[1.0, 0.0, 0.0]] * 2, dtype=torch.float64)
        out = reflect_volume(v, n, torch.zeros(2, dtype=torch.float64), mode="nearest")
        assert torch.allclose(out, v.flip(2))
        n = torch.tensor([[0.0, 0.0, 1.0]] * 2, dtype=torch.float64)
        assert torch.allclose(reflect_volume(v, n, torch.zeros(2, dtype=torch.float64), mode="nearest"), v.flip(4))

    def test_sdf_moves_to_mirror(self):
        # an SDF of a sphere at (0.2, 0.1, 0) reflected about x = 0.05 is the sphere at (-0.1, 0.1, 0)
        shape = (24, 24, 24)
        v = _sdf(shape, [0.2, 0.1, 0.0])
        out = reflect_volume(v, torch.tensor([[2.0, 0.0, 0.0]], dtype=torch.float64), torch.tensor([-0.1], dtype=torch.float64))
        ref = _sdf(shape, [-0.1, 0.1, 0.0])
        inner = (slice(None), slice(None), slice(2, -2), slice(2, -2), slice(2, -2))
        assert (out - ref)[inner].abs().max() < 0.02  # trilinear interpolation of a smooth field

    def test_oblique_2d(self):
        v = _sdf((32, 32), [0.2, 0.0])
        n = torch.tensor([[1.0, 1.0]], dtype=torch.float64)  # plane x + y = 0: (0.2, 0) -> (0, -0.2)
        out = reflect_volume(v, n, torch.zeros(1, dtype=torch.float64))
        assert (out - _sdf((32, 32), [0.0, -0.2]))[..., 2:-2, 2:-2].abs().max() < 0.02

    def test_gradcheck(self):
        v = torch.randn(1, 1, 4, 5, 3, dtype=torch.float64, requires_grad=True)
        n = torch.tensor([[0.8, 0.5, 0.3]], dtype=torch.float64, requires_grad=True)
        b = torch.tensor([0.05], dtype=torch.float64, requires_grad=True)
        assert torch.autograd.gradcheck(lambda v, n, b: reflect_volume(v, n, b, padding_mode="zeros"), (v, n, b))

    def test_exception(self):
        with pytest.raises(InputShapeError, match="normal: expected \\(1, 3\\)"):
            reflect_volume(torch.ones(1, 1, 2, 2, 2), torch.ones(1, 2), torch.zeros(1))


def test_bfloat16():
    v = _sdf((8, 8, 8), [0.1, 0.0, 0.0]).float()
    n, b = torch.tensor([[1.0, 0.2, 0.0]]), torch.tensor([0.02])
    out = reflect_volume(v.bfloat16(), n.bfloat16(), b.bfloat16())
    assert out.dtype == torch.bfloat16
    assert torch.allclose(out.float(), reflect_volume(v, n, b), atol=0.03)
