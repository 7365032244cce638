import numpy as np
import pytest
import torch

from torchsym.core.checks import (
    as_tensor,
    check_dense,
    check_image,
    check_int,
    check_points,
    check_positive,
    check_scale,
    scale_problem,
)
from torchsym.errors import InputShapeError, InputValueError, TorchsymError


def _gen(seed: int = 0) -> torch.Generator:
    return torch.Generator().manual_seed(seed)


class TestCheckPoints:
    def test_smoke(self):
        pts = check_points(np.zeros((5, 3)), dim=3, min_points=4)
        assert isinstance(pts, torch.Tensor) and pts.shape == (5, 3) and pts.dtype == torch.float64

    def test_keeps_dtype(self):
        assert check_points(torch.zeros(4, 3, dtype=torch.float32)).dtype == torch.float32

    def test_integer_becomes_float(self):
        assert check_points(torch.zeros(4, 3, dtype=torch.int64)).is_floating_point()

    def test_exception_shape(self):
        with pytest.raises(InputShapeError, match=r"points: expected \(N, D\) with D = 3 and N >= 4, got \(3, 2\)"):
            check_points(torch.zeros(3, 2), dim=3, min_points=4)

    def test_exception_nan(self):
        x = torch.zeros(5, 3)
        x[2, 1] = float("nan")
        with pytest.raises(InputValueError, match=r"points: expected finite values, got 1 NaN or infinite entries \(first at index \(2, 1\)\)"):
            check_points(x)

    def test_error_hierarchy(self):
        with pytest.raises(ValueError):
            check_points(torch.zeros(2))
        with pytest.raises(TorchsymError):
            check_points(torch.zeros(2))

    def test_exception_not_numeric(self):
        with pytest.raises(InputShapeError, match="points: expected a tensor or array, got str"):
            check_points("abc")


class TestCheckImage:
    def test_ranks(self):
        assert check_image(torch.rand(8, 9, generator=_gen())).shape == (1, 1, 8, 9)
        assert check_image(torch.rand(3, 8, 9, generator=_gen())).shape == (1, 3, 8, 9)
        assert check_image(torch.rand(2, 1, 8, 9, generator=_gen())).shape == (2, 1, 8, 9)

    def test_uint8_scaled(self):
        img = check_image(np.full((4, 4), 255, dtype=np.uint8))
        assert float(img.max()) == 1.0

    def test_exception_channels(self):
        with pytest.raises(InputShapeError, match=r"image: expected 1 or 3 channels in \(B, C, H, W\), got \(1, 5, 8, 8\)"):
            check_image(torch.rand(1, 5, 8, 8, generator=_gen()))


class TestScalars:
    def test_int(self):
        assert check_int(3, "k", minimum=1) == 3
        with pytest.raises(InputValueError, match="k: expected an integer >= 1, got 0"):
            check_int(0, "k", minimum=1)
        with pytest.raises(InputValueError, match="k: expected an integer, got 2.5"):
            check_int(2.5, "k")

    def test_positive(self):
        with pytest.raises(InputValueError, match="sigma: expected a positive number, got -1"):
            check_positive(-1, "sigma")

    def test_as_tensor_list(self):
        assert as_tensor([[1, 2], [3, 4]], "x").dtype == torch.float64


class TestCheckDense:
    def test_smoke(self):
        assert check_dense(torch.zeros(3), "x").shape == (3,)

    @pytest.mark.parametrize("make, message", [
        (lambda: torch.zeros(5, 3).to_sparse(), "expected a dense tensor, got layout torch.sparse_coo"),
        (lambda: torch.zeros(5, 3).to_sparse_csr(), "expected a dense tensor, got layout torch.sparse_csr"),
        (lambda: torch.empty(5, 3, device="meta"), "expected a tensor holding data, got one on the meta device"),
    ])
    def test_exception(self, make, message):
        with pytest.raises(InputShapeError, match=f"points: {message}"):
            check_points(make())

    def test_big_endian_array(self):
        assert as_tensor(np.arange(6, dtype=">f8").reshape(2, 3), "x").tolist() == [[0, 1, 2], [3, 4, 5]]

    def test_float128_array(self):
        with pytest.raises(InputShapeError, match="x: expected a float, integer or boolean array"):
            as_tensor(np.zeros(3, dtype=np.longdouble), "x")


class TestScale:
    def test_smoke(self):
        pts = torch.rand(100, 3, generator=_gen())
        assert scale_problem(pts) is None and check_scale(pts, "points") is pts

    def test_stray_point(self):
        pts = torch.rand(1000, 3, generator=_gen())
        pts[17] = 1e20
        with pytest.raises(InputValueError, match=r"points: point 17 lies 1e\+20 from the median point.*far outside the rest"):
            check_scale(pts, "points")

    def test_far_but_representable_outlier_kept(self):
        pts = torch.rand(1000, 3, generator=_gen(), dtype=torch.float64)
        pts[3] = 1e6  # far, but the rest is still far above float64's rounding
        assert scale_problem(pts) is None

    def test_overflowing_scale(self):
        pts = torch.rand(50, 3, generator=_gen(), dtype=torch.float64) * 1e200
        with pytest.raises(InputValueError, match=r"x: coordinates up to .*e\+(199|200) overflow torch.float64 in sums of squares"):
            check_scale(pts, "x")

    def test_coincident_points(self):
        assert scale_problem(torch.zeros(10, 3)) is None
