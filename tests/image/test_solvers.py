"""Both image solvers: registry, configs, settings, the default pipeline, real photos."""

from __future__ import annotations

from pathlib import Path

import pytest
import torch

import torchsym
from torchsym.errors import ConfigError
from torchsym.image import (
    BoundaryCliqueDetector,
    BoundaryCliquesSettings,
    KSymmetryDetector,
    KSymmetrySettings,
    ReflectionAxesResult,
    boundary_clique_axes,
    ksymmetry_axes,
)
from torchsym.io import read_image

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


class TestRegistryAndConfigs:
    def test_registered(self):
        names = torchsym.SOLVERS.names("image")
        assert "ksymmetry" in names and "boundary_cliques" in names
        assert torchsym.SOLVERS.default_for("image").name == "axes"

    @pytest.mark.parametrize("name", ["image_ksymmetry.yaml", "image_boundary_cliques.yaml"])
    def test_config_builds(self, name):
        pipe = torchsym.build_pipeline(torchsym.load_config(CONFIGS / name))
        assert pipe is not None

    def test_detect_default(self, single_objects):
        img, _ = single_objects[0]
        res = torchsym.detect(img)
        assert isinstance(res, ReflectionAxesResult)
        assert res.method == torchsym.SOLVERS.default_for("image").name


class TestRealPhotos:
    def test_one_dev_photo(self, shared_data):
        folder = shared_data / "images" / "reflection_single_dev"
        if not folder.is_dir():
            pytest.skip(f"{folder} is absent")
        img = read_image(folder / "refs_039.jpg")
        res = torchsym.image.boundary_clique_axes(img)
        assert res.image_size == tuple(img.shape[-2:]) and res.axes.shape[0] >= 1


class TestSettings:
    @pytest.mark.parametrize(("fn", "cls"), [(boundary_clique_axes, BoundaryCliqueDetector), (ksymmetry_axes, KSymmetryDetector)])
    def test_function_and_module_agree(self, fn, cls, single_objects):
        img, _ = single_objects[1]
        a, b = fn(img, max_axes=2), cls(max_axes=2)(img)
        assert torch.equal(a.axes, b.axes) and torch.equal(a.scores, b.scores) and torch.equal(a.pairs, b.pairs)

    def test_groups_and_renames(self):
        s = BoundaryCliquesSettings.from_dict({"max_boundary_pairs": 100, "sift": {"enabled": False}, "cliques": {"solver": "highs"}})
        assert s.max_boundary_pairs == 100 and not s.use_sift and s.cliques.solver == "highs"
        assert BoundaryCliquesSettings().use_sift and not BoundaryCliquesSettings(score="support").use_sift
        k = KSymmetrySettings().replace({"clustering.max_iters": 7, "pairs.max_keypoints": 10})
        assert k.clustering.max_iters == 7 and k.pairs.max_keypoints == 10
        assert "pairs.k1=2" in repr(KSymmetryDetector(pairs={"k1": 2}))

    def test_exception(self):
        with pytest.raises(ConfigError, match="max_pairs: unknown setting of BoundaryCliquesSettings"):
            BoundaryCliqueDetector(max_pairs=30)
        with pytest.raises(ConfigError, match="max_iter: unknown setting of KSymmetrySettings"):
            ksymmetry_axes(torch.rand(1, 32, 32), max_iter=3)
        with pytest.raises(ConfigError, match="sift.enabled: needs score='gradient'"):
            BoundaryCliquesSettings(score="support", sift={"enabled": True})
        with pytest.raises(ConfigError, match="clustering.max_iters: expected an int >= 1, got 0"):
            KSymmetryDetector(clustering={"max_iters": 0})


class TestRequiresGrad:
    """Issue 31: an image that requires grad is detected like its detached copy."""

    @pytest.mark.parametrize("fn", [boundary_clique_axes, ksymmetry_axes])
    def test_requires_grad(self, fn, single_objects):
        img, _ = single_objects[0]
        res = fn(img.clone().requires_grad_(True))
        assert torch.equal(res.axes, fn(img).axes) and not res.axes.requires_grad


def _smoothed_noise(seed: int) -> torch.Tensor:
    """``(3, 240, 320)`` uniform noise blurred by a 7 x 7 box twice, stretched to [0, 1]."""
    noise = torch.rand(1, 1, 240, 320, generator=torch.Generator().manual_seed(seed))
    for _ in range(2):
        noise = torch.nn.functional.avg_pool2d(noise, 7, stride=1, padding=3, count_include_pad=False)
    noise = (noise - noise.min()) / (noise.max() - noise.min())
    return noise[0].expand(3, -1, -1).contiguous()


SCORE_MODES = [
    (boundary_clique_axes, {}),
    (boundary_clique_axes, {"score": "support", "edges": {"detector": "canny"}, "theta": 5.0}),
    (boundary_clique_axes, {"score": "photometric"}),
    (ksymmetry_axes, {}),
    (ksymmetry_axes, {"score": "support"}),
]


class TestScores:
    """Scores rank axes across photographs: bounded, and low on smoothed noise."""

    @pytest.mark.parametrize(("fn", "kw"), SCORE_MODES)
    def test_in_unit_interval(self, fn, kw, three_objects):
        res = fn(three_objects[0], **kw)
        assert len(res) >= 1 and bool(((res.scores >= 0) & (res.scores <= 1)).all())

    @pytest.mark.parametrize(("fn", "kw"), SCORE_MODES)
    def test_smoothed_noise_scores_low(self, fn, kw):
        for seed in range(2):
            res = fn(_smoothed_noise(seed), **kw)
            assert bool((res.scores < 0.3).all()), (seed, res.scores.tolist())

    def test_symmetric_object_beats_noise(self, single_objects):
        img, _ = single_objects[0]
        assert float(boundary_clique_axes(img).scores[0]) > 0.3
