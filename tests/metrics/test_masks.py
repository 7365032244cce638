import numpy as np
import pytest
import torch

from torchsym.errors import InputShapeError, InputValueError
from torchsym.metrics.masks import best_reflection_iou, reflection_iou


def _l_shape():
    m = np.zeros((4, 4), bool)
    m[0, 0] = m[0, 1] = m[1, 0] = True  # pixels (x, y) = (0, 0), (1, 0), (0, 1)
    return m


class TestReflectionIou:
    def test_smoke(self):
        m = np.zeros((6, 6), bool)
        m[1:3, 1:5] = True  # columns 1..4: symmetric about x = 2.5
        assert reflection_iou(m, [1.0, 0.0], -2.5) == 1.0
        assert reflection_iou(torch.from_numpy(m), torch.tensor([2.0, 0.0]), -5.0) == 1.0  # normal scaled with offset

    def test_value(self):
        m = _l_shape()
        # about x = 0.5: (0,0) <-> (1,0) land on the mask, (0,1) -> (1,1) does not: 2 / (3 + 3 - 2)
        assert reflection_iou(m, [1.0, 0.0], -0.5) == pytest.approx(0.5)
        # about y = x every pixel lands on the mask
        assert reflection_iou(m, [1.0, -1.0], 0.0) == pytest.approx(1.0)
        # about x = 3.5 every pixel leaves the 4 x 4 image: (0, y) -> (7, y)
        assert reflection_iou(m, [1.0, 0.0], -3.5) == 0.0

    def test_best(self):
        m = np.zeros((40, 40), bool)
        for r in range(5, 35):
            m[r, 5 : 40 - r] = True  # x, y >= 5 and x + y <= 39: symmetric about y = x only
        iou, normal, offset = best_reflection_iou(m)
        assert iou == pytest.approx(1.0)
        assert normal[0] == pytest.approx(-(0.5**0.5)) and normal[1] == pytest.approx(0.5**0.5)  # the axis y = x
        assert offset == pytest.approx(0.0, abs=1e-9)  # through the centroid, which lies on y = x
        assert best_reflection_iou(np.zeros((3, 3), bool))[0] == 0.0

    def test_exception(self):
        with pytest.raises(InputShapeError, match="mask: expected an \\(H, W\\)"):
            reflection_iou(np.zeros(5), [1.0, 0.0], 0.0)
        with pytest.raises(InputValueError, match="normal"):
            reflection_iou(np.zeros((3, 3)), [0.0, 0.0], 0.0)
        with pytest.raises(InputValueError, match="angle_step"):
            best_reflection_iou(np.zeros((3, 3)), angle_step=0.0)
