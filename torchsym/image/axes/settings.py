"""Settings of the axis stage (thesis Ch. 2; the photometric test after Cicconet et al. 2017)."""

from __future__ import annotations

import dataclasses

from torchsym.core.settings import Settings, group, setting
from torchsym.image.boundary_cliques.settings import BoundaryCliquesSettings

__all__ = ["AxisStageSettings", "Border", "Decision", "Photometric", "Refine", "Registration"]


@dataclasses.dataclass(frozen=True)
class Border(Settings):
    """The part of the image every score of the stage is taken on: the image less its
    constant frame and a band inside it (:func:`~torchsym.image.axes.border.content_box`)."""

    tolerance: float = setting(0.01, "a border row or column this close to the first one's colour everywhere is "
                               "part of a constant frame", low=0.0)
    margin: float = setting(0.03, "the band left out inside the frame or the image's border", unit="x shorter side",
                            low=0.0)
    min_band: int = setting(4, "the least band", unit="px", low=0)


@dataclasses.dataclass(frozen=True)
class Photometric(Settings):
    """The image against its reflection over each axis's support
    (:func:`~torchsym.image.axes.mirror_ncc.mirror_ncc`)."""

    side: int = setting(256, "longer side of the pyramid level the test runs on", unit="px", low=32)
    band_sigma: float = setting(8.0, "the test compares the level minus its Gaussian blur of this sigma (a band-pass: "
                                "shading and flat regions carry no weight); 0: the level itself",
                                unit="px at the level", low=0.0)
    width: float = setting(2.0, "half-width of the support across the axis", unit="x half-length", low=0.0, low_open=True)
    n_along: int = setting(32, "samples along each axis", low=2)
    n_across: int = setting(16, "samples across each half of the support", low=1)


@dataclasses.dataclass(frozen=True)
class Registration(Settings):
    """The photograph registered with its mirror image over every axis direction by FFT
    (:func:`~torchsym.image.axes.global_mirror.mirror_map`): its best axes join the
    candidates, its correlation is a feature of every candidate."""

    side: int = setting(128, "longer side of the (grey) level the registration runs on", unit="px", low=32)
    band_sigma: float = setting(4.0, "the level minus its Gaussian blur of this sigma; 0: the level itself",
                                unit="px at the level", low=0.0)
    n_angles: int = setting(90, "axis directions in [0, 180) deg", low=4)
    min_overlap: float = setting(0.25, "the least overlap of the image and its mirror", unit="x image area", low=0.0,
                                 high=1.0)
    count: int = setting(3, "best axes of the registration that join the candidates (0 with decision.w_registration 0: "
                         "no registration at all)", low=0)
    extent_threshold: float = setting(0.2, "their extent: the run along the line whose local mirror correlation "
                                      "stays at or above this (:func:`~torchsym.image.axes.extent.grow_extent`)",
                                      low=-1.0, high=1.0)


@dataclasses.dataclass(frozen=True)
class Refine(Settings):
    """Angle and offset moved to the best photometric score, coarse to fine
    (:func:`~torchsym.image.axes.refine.refine_axes`)."""

    angle_step: float = setting(2.0, "first round's angle step", unit="deg", low=0.0, low_open=True)
    offset_step: float = setting(0.02, "first round's offset step", unit="x longer side", low=0.0, low_open=True)
    rounds: int = setting(0, "rounds, each halving both steps (0: no refinement; it did not help on the butterflies: docs/design/axes.md)", low=0, high=8)
    steps: int = setting(2, "steps each way per round", low=1)
    passes: int = setting(1, "refinement then extent, this many times", low=1)
    extent_threshold: float | None = setting(
        None, "local mirror correlation down to which an axis's extent grows along its line "
        "(:func:`~torchsym.image.axes.extent.grow_extent`); null: the candidate's extent", low=-1.0, high=1.0)


@dataclasses.dataclass(frozen=True)
class Decision(Settings):
    """The calibrated score ``sigmoid(intercept + w_contrast contrast + w_length log(length)
    + w_evidence sqrt(evidence))`` and its threshold
    (:func:`~torchsym.image.axes.decision.calibrated_score`). The weights are a logistic fit
    (axis right under the challenge criterion or not) on 202 Leeds butterflies (the
    ``choose`` half, ``benchmarks/axes_data.py``), the threshold the one of best pooled F
    there; ``benchmarks/results/axes.md``."""

    intercept: float = setting(-2.871, "logistic intercept")
    w_contrast: float = setting(2.319, "weight of the contrast: correlation minus the mean of the support turned by "
                                "30..150 deg")
    w_length: float = setting(0.692, "weight of log(segment length / longer side)")
    w_evidence: float = setting(3.938, "weight of the square root of the candidate's mirrored-gradient evidence "
                                "(boundary cliques' score, in [0, 1])")
    w_registration: float = setting(0.0, "weight of the registration's correlation at the axis "
                                    "(:func:`~torchsym.image.axes.global_mirror.axis_correlation`)", low=-100.0, high=100.0)
    w_from_map: float = setting(0.0, "added for an axis found by the registration rather than by the candidates",
                                low=-100.0, high=100.0)
    threshold: float = setting(0.175, "calibrated score at or above which an axis is accepted", low=0.0, high=1.0)
    second_threshold: float = setting(0.5, "an axis after the best is accepted only at or above this too (one "
                                      "symmetric subject, one accepted axis; benchmarks/results/axes_pool.md)",
                                      low=0.0, high=1.0)
    duplicate_angle: float = setting(6.0, "a refined axis this close in angle to a better one...", unit="deg",
                                     low=0.0, high=90.0, low_open=True)
    duplicate_distance: float = setting(0.03, "...with its centre this close to the better's line is the same axis",
                                        unit="x longer side", low=0.0, low_open=True)


@dataclasses.dataclass(frozen=True)
class AxisStageSettings(Settings):
    """Settings of :func:`~torchsym.image.axes.image_axes`: candidates, test, refinement, decision."""

    candidates: BoundaryCliquesSettings = group(BoundaryCliquesSettings, "the candidate axes (boundary cliques and "
                                                "mirrored-SIFT pairs, thesis Secs. 2.2-2.3)")
    border: Border = group(Border)
    photometric: Photometric = group(Photometric)
    registration: Registration = group(Registration)
    refine: Refine = group(Refine)
    decision: Decision = group(Decision)
    max_axes: int = setting(20, "the most axes kept in the ranked list", low=1)
