"""Duplicate suppression of axes (torchsym.image.suppression)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from torchsym.errors import InputShapeError, InputValueError
from torchsym.image.suppression import suppress_duplicates


def _line(angle_deg: float, through) -> np.ndarray:
    """Line whose normal is at ``angle_deg``, through the point ``through``."""
    n = np.array([math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))])
    return np.array([n[0], n[1], -n @ np.asarray(through, dtype=np.float64)])


class TestSuppressDuplicates:
    def test_same_object_kept_once(self):
        base = _line(0.0, (100, 100))
        near = _line(4.0, (100, 103))  # 4 deg and 3 px off, same stretch of the line
        assert suppress_duplicates([base, near], [(-50.0, 50.0), (-45.0, 55.0)], [1.0, 2.0]) == [1]
        assert suppress_duplicates([base, near], [(-50.0, 50.0), (-45.0, 55.0)], [3.0, 2.0]) == [0]

    def test_distinct_axes_kept(self):
        base = _line(0.0, (100, 100))
        cases = [
            (_line(20.0, (100, 100)), (-50.0, 50.0)),  # turned beyond 10 deg
            (_line(0.0, (130, 100)), (-50.0, 50.0)),  # parallel, 30 px away
            (base.copy(), (80.0, 160.0)),  # same line, another object further along it
        ]
        for other, extent in cases:
            assert suppress_duplicates([base, other], [(-50.0, 50.0), extent], [2.0, 1.0]) == [0, 1]

    def test_by_angle_and_containment(self):
        base = _line(0.0, (100, 100))
        turned = _line(30.0, (100, 100))  # same centre, 30 deg apart
        assert suppress_duplicates([base, turned], [(-50.0, 50.0), (-50.0, 50.0)], [2.0, 1.0]) == [0, 1]
        # a short segment inside the end of a long one on the same line is the same axis
        assert suppress_duplicates([base, base.copy()], [(-100.0, 100.0), (60.0, 100.0)], [2.0, 1.0]) == [0]
        with pytest.raises(InputShapeError, match="lines, extents, scores"):
            suppress_duplicates([base], [(-1.0, 1.0)], [1.0, 2.0])
        with pytest.raises(InputShapeError, match="lines"):
            suppress_duplicates([base[:2]], [(-1.0, 1.0)], [1.0])
        with pytest.raises(InputValueError, match="angle"):
            suppress_duplicates([base], [(-1.0, 1.0)], [1.0], angle=-1.0)
