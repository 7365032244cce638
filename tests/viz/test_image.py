"""Pictures of reflection axes (torchsym.viz.image)."""

from __future__ import annotations

import torch

from torchsym.image.results import ReflectionAxesBatch, build_result, empty_result
from torchsym.io import read_image
from torchsym.viz import write_artifacts
from torchsym.viz.image import draw_axes


def _result():
    pairs = torch.tensor([[40.0, 20.0, 60.0, 20.0], [45.0, 70.0, 55.0, 70.0], [1.0, 1.0, 3.0, 3.0]])
    lines = [torch.tensor([1.0, 0.0, -50.0], dtype=torch.float64), torch.tensor([0.0, 1.0, -40.0], dtype=torch.float64)]
    return build_result(lines, [torch.tensor([0, 1]), torch.tensor([2])], [2.0, 0.5], pairs, 100, 120, "test",
                        extents=[None, (-100.0, 100.0)])


class TestWriteArtifacts:
    def test_smoke(self, tmp_path):
        paths = write_artifacts(_result(), torch.rand(3, 100, 120), tmp_path, "photo")
        assert [p.name for p in paths] == ["photo_axes.png"]
        drawn = read_image(paths[0])
        assert drawn.shape[0] == 3 and drawn.shape[2] >= 120

    def test_best_axis_drawn_in_red(self):
        arr = draw_axes(torch.zeros(3, 100, 120), _result(), n_pairs=0)  # (H', W', 3), scaled up to 900 wide
        h, w = arr.shape[:2]
        column = arr[int(0.5 * h), int((50 + 0.5) / 120 * w) - 3 : int((50 + 0.5) / 120 * w) + 4].astype(int)
        assert ((column[:, 0] > 200) & (column[:, 1] < 120)).any()  # red on the line x = 50

    def test_batch_and_empty(self, tmp_path):
        batch = ReflectionAxesBatch((_result(), empty_result(100, 120, "test")))
        paths = write_artifacts(batch, torch.rand(2, 1, 100, 120), tmp_path, "b")
        assert [p.name for p in paths] == ["b_0_axes.png", "b_1_axes.png"] and all(p.stat().st_size > 0 for p in paths)


def test_no_accepted_axis_is_said_on_the_picture():
    import dataclasses

    import torch

    from torchsym.image.results import ReflectionAxesResult
    from torchsym.viz.image import draw_axes

    res = ReflectionAxesResult(axes=torch.tensor([[10.0, 5.0, 10.0, 50.0]]), scores=torch.tensor([0.05]),
                               lines=torch.tensor([[1.0, 0.0, -10.0]]), pairs=torch.zeros(0, 4),
                               pair_axis=torch.zeros(0, dtype=torch.int64), image_size=(64, 64), method="axes",
                               accepted=torch.tensor([False]))
    img = torch.rand(3, 64, 64)
    none = draw_axes(img, res)
    one = draw_axes(img, dataclasses.replace(res, accepted=torch.tensor([True])))
    assert none.shape == one.shape and not (none == one).all()
    assert "no axis accepted" in res.summary()
