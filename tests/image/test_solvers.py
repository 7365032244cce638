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
        assert torchsym.SOLVERS.default_for("image").name in ("ksymmetry", "boundary_cliques")

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
