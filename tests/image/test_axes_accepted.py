"""The methods that read the axis stage take its settings from their own (issue 56, item 6)."""

from __future__ import annotations

import pytest
import torch

import torchsym
from torchsym.errors import ConfigError
from torchsym.image.axes import AxisStageSettings
from torchsym.image.axes.accepted import accepted_axes, stage_axes_found
from torchsym.image.symmetry_map.settings import SymmetryMapSettings
from torchsym.image.symmslic.settings import SymmSlicSettings


class TestAcceptedAxes:
    def test_smoke(self, single_objects):
        img, _ = single_objects[0]
        lines, pairs = accepted_axes(img[None], AxisStageSettings())
        assert lines.shape[1] == 3 and len(pairs) == lines.shape[0] >= 1

    def test_best_when_none_accepted(self, single_objects):
        img, _ = single_objects[0]
        strict = AxisStageSettings.from_dict({"decision": {"threshold": 1.0}})
        lines, _ = accepted_axes(img[None], strict)
        assert lines.shape[0] == 1

    def test_generator_passed_through(self, single_objects):
        img, _ = single_objects[1]
        a = accepted_axes(img[None], AxisStageSettings(), generator=torch.Generator().manual_seed(3))[0]
        b = accepted_axes(img[None], AxisStageSettings(), generator=torch.Generator().manual_seed(3))[0]
        assert torch.equal(a, b)

    def test_symmslic_scores_0_about_an_axis_the_stage_did_not_accept(self):
        noise = torch.rand(3, 160, 160, generator=torch.Generator().manual_seed(5))
        lines, _, accepted = stage_axes_found(noise[None], AxisStageSettings())
        res = torchsym.symm_slic(noise)
        if not accepted and len(lines):
            assert res.score == 0.0 and any("accepted no axis" in n for n in res.notes)
        assert res.score < 0.3  # without symmetry, low either way


class TestNestedGroup:
    @pytest.mark.parametrize("cls", [SymmSlicSettings, SymmetryMapSettings])
    def test_from_dict(self, cls):
        s = cls.from_dict({"axes": {"decision": {"threshold": 0.4}, "border": {"margin": 0.05}}})
        assert s.axes.decision.threshold == 0.4 and s.axes.border.margin == 0.05
        with pytest.raises(ConfigError):
            cls.from_dict({"axes": {"decision": {"treshold": 0.4}}})

    @pytest.mark.parametrize(("solver", "module"), [("symmslic", "torchsym.image.symmslic.solver"),
                                                      ("symmetry_map", "torchsym.image.symmetry_map.estimate")])
    def test_method_uses_its_axes_settings(self, solver, module, monkeypatch, single_objects):
        import importlib

        seen = []
        mod = importlib.import_module(module)

        def spy(image, settings, *, generator=None):
            seen.append((settings, generator))
            return torch.zeros(0, 3), []

        def spy_found(image, settings, *, generator=None):
            return (*spy(image, settings, generator=generator), False)

        name = "stage_axes_found" if hasattr(mod, "stage_axes_found") else "accepted_axes"
        monkeypatch.setattr(mod, name, spy_found if name == "stage_axes_found" else spy)
        img, _ = single_objects[2]
        config = {"input": "image", "steps": [{"name": solver, "params": {"axes": {"decision": {"threshold": 0.42}}}}]}
        torchsym.detect(img, config)
        assert seen and seen[0][0].decision.threshold == 0.42 and seen[0][1] is not None
