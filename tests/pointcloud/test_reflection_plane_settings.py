"""torchsym.pointcloud.reflection_plane.settings and the configs that set them."""

from pathlib import Path

import pytest

import torchsym
from torchsym.core.config import build_pipeline, load_config
from torchsym.errors import ConfigError
from torchsym.pointcloud import ReflectionPlaneDetector, ReflectionPlaneSettings

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


class TestReflectionPlaneSettings:
    def test_smoke(self):
        s = ReflectionPlaneSettings()
        assert s.n_starts == 40 and s.init.n_samples == 500 and s.alternation.max_iters == 100
        assert s.polish.enabled and s.kernel.enabled and s.prealign.enabled

    def test_registry_reads_the_settings(self):
        entry = torchsym.SOLVERS.get("reflection_plane")
        assert entry.settings_class is ReflectionPlaneSettings
        assert entry.defaults() == ReflectionPlaneSettings().to_dict()
        assert ReflectionPlaneDetector().settings == ReflectionPlaneSettings()

    def test_angles_in_degrees(self):
        units = {name: unit for name, _, _, unit, _ in ReflectionPlaneSettings.describe()}
        for name in ("alternation.tol_angle", "prealign.tol_angle", "kernel.tol_angle", "init.grid_step", "starts.min_separation"):
            assert units[name] == "deg"

    @pytest.mark.parametrize(
        "params, message",
        [
            ({"alternation": {"max_iter": 3}}, r"alternation.max_iter: unknown setting .*did you mean 'max_iters'"),
            ({"kernel_stage": False}, "kernel_stage: unknown setting"),
            ({"starts": {"accept": 1.5}}, r"starts.accept: expected a finite number >= 0.0 and <= 1.0, got 1.5"),
            ({"alternation": {"update": "svd"}}, "alternation.update: expected one of 'reflection', 'procrustes'"),
        ],
    )
    def test_exception(self, params, message):
        with pytest.raises(ConfigError, match=message):
            load_config({"input": "pointcloud", "steps": [{"name": "reflection_plane", "params": params}]})

    def test_thesis_config(self):
        det = build_pipeline(CONFIGS / "pointcloud_plane_thesis.yaml").steps[0]
        s = det.settings
        assert s.n_starts == 1 and s.init.directions == "grid" and not s.starts.pca
        assert not s.prealign.enabled and not s.polish.enabled and not s.kernel.enabled
        assert s.alternation.update == "procrustes" and not s.alternation.accelerate

    def test_default_config_is_the_defaults(self):
        det = build_pipeline(CONFIGS / "pointcloud_plane.yaml").steps[0]
        assert det.settings == ReflectionPlaneSettings()
