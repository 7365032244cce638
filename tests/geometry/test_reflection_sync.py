"""The zero-normal check reads a value back only for CPU tensors outside torch.compile."""

import pytest
import torch

from torchsym.errors import InputValueError
from torchsym.geometry import plane_distance, point_plane_distance, reflect_points


def test_no_host_read_off_cpu():
    # meta tensors have no values: any bool(...) on them raises, so passing shows no read-back
    x, n = torch.zeros(4, 3, device="meta"), torch.zeros(3, device="meta")
    assert reflect_points(x, n).shape == (4, 3)
    assert point_plane_distance(x, n).shape == (4,)
    assert plane_distance(n, 0.0, n, 0.0).shape == ()


def test_cpu_still_checked():
    with pytest.raises(InputValueError, match="normal: expected a non-zero vector"):
        reflect_points(torch.zeros(4, 3), torch.zeros(3))


def test_compiled_no_check():
    fn = torch.compile(reflect_points, backend="eager", fullgraph=True)
    out = fn(torch.ones(2, 3), torch.tensor([1.0, 0.0, 0.0]))
    assert torch.allclose(out, torch.tensor([[-1.0, 1.0, 1.0]] * 2))
