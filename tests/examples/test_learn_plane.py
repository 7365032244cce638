"""A shortened run of examples/learn_plane.py: random starts learn the chair's plane."""

import importlib.util
import math
from pathlib import Path

import pytest
import torch

from torchsym.geometry import plane_angle

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "learn_plane.py"


def _load():
    spec = importlib.util.spec_from_file_location("learn_plane", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.slow
def test_learn_plane_short():
    mod = _load()
    gen = torch.Generator().manual_seed(0)
    points, n_true, _ = mod.prepare(300, gen)
    normal, offset, final, history = mod.learn(points, 4, 100, 0.03, gen)
    best = int(final.argmin())
    assert math.degrees(float(plane_angle(normal[best], n_true))) < 1.0
    assert float(final[best]) < float(history[0].min())
