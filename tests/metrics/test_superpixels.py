import numpy as np
import pytest

from torchsym.errors import InputShapeError, InputValueError
from torchsym.metrics.superpixels import segmentation_error


class TestSegmentationError:
    def setup_method(self):
        self.truth = np.zeros((10, 10), int)
        self.truth[2:6, 2:6] = 1  # 16 px, bounding box 4 x 4
        self.mask = self.truth.copy()
        self.mask[2, 2] = 0  # a miss inside the box
        self.mask[8, 8] = 1  # a false alarm outside it

    def test_value(self):
        e = segmentation_error(self.mask, self.truth)
        assert e["over_image"] == pytest.approx(2 / 100) and e["over_box"] == pytest.approx(2 / 16)

    def test_box(self):
        e = segmentation_error(self.mask, self.truth, box=(1, 1, 7, 7))  # 6 x 6 = 36 px
        assert e["over_box"] == pytest.approx(2 / 36)

    def test_ignore(self):
        ignore = np.zeros((10, 10), bool)
        ignore[8, 8] = True  # the false alarm is not counted, nor is the pixel
        ignore[1, 1] = True  # an ignored pixel inside the box leaves the box's count
        e = segmentation_error(self.mask, self.truth, box=(1, 1, 7, 7), ignore=ignore)
        assert e["over_image"] == pytest.approx(1 / 98) and e["over_box"] == pytest.approx(1 / 35)

    def test_perfect(self):
        assert segmentation_error(self.truth, self.truth) == {"over_image": 0.0, "over_box": 0.0}

    def test_exception(self):
        with pytest.raises(InputValueError, match="box"):
            segmentation_error(self.mask, self.truth, box=(5, 1, 5, 7))
        with pytest.raises(InputShapeError, match="ignore"):
            segmentation_error(self.mask, self.truth, ignore=np.zeros((3, 3)))
