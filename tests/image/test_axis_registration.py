"""The registration of a photograph with its mirror image by FFT (issue 56, item 1)."""

from __future__ import annotations

import math
import time

import pytest
import torch
import torch.nn.functional as F

from torchsym.image.axes import AxisStageSettings, image_axes
from torchsym.image.axes.global_mirror import axis_correlation, map_peaks, mirror_map
from torchsym.image.axes.level import band_level
from torchsym.image.axes.mirror_ncc import AxisParams


def mirrored_image(seed: int, angle_deg: float, offset: float, h: int = 180, w: int = 240):
    """Smooth random colours made exactly mirror-symmetric about the line of direction
    ``angle_deg`` at ``offset`` px along its normal from the image's centre: ``(image (3, h, w),
    a point of the line (2,), angle rad)``."""
    g = torch.Generator().manual_seed(seed)
    img = F.interpolate(torch.rand(1, 3, h // 8, w // 8, generator=g), size=(h, w), mode="bilinear", align_corners=False)[0]
    img = img + 0.1 * torch.rand(3, h, w, generator=g)
    phi = math.radians(angle_deg)
    n = torch.tensor([-math.sin(phi), math.cos(phi)])
    c = torch.tensor([(w - 1) / 2, (h - 1) / 2]) + offset * n
    yy, xx = torch.meshgrid(torch.arange(h).float(), torch.arange(w).float(), indexing="ij")
    p = torch.stack([xx, yy], -1)
    d = ((p - c) * n).sum(-1)
    q = p - 2 * d[..., None] * n
    grid = torch.stack([2 * q[..., 0] / (w - 1) - 1, 2 * q[..., 1] / (h - 1) - 1], -1)
    mirror = F.grid_sample(img[None], grid[None], align_corners=True)[0]
    keep = (d < 0) & (grid.abs() <= 1).all(-1)
    return torch.where(keep, mirror, img).clamp(0, 1), c, phi


def _line_error(angle: float, centre: torch.Tensor, true_point: torch.Tensor, true_angle: float) -> tuple[float, float]:
    """``(angle error deg, distance of the found centre from the true line px)``."""
    da = math.degrees(abs(math.remainder(angle - true_angle, math.pi)))
    n = torch.tensor([-math.sin(true_angle), math.cos(true_angle)])
    return da, float(((centre - true_point) * n).sum().abs())


class TestMirrorMap:
    @pytest.mark.parametrize(("angle", "offset"), [(90.0, 0.0), (90.0, 20.0), (30.0, -15.0), (0.0, 10.0), (137.0, 5.0)])
    def test_exact_mirror_angle_and_offset(self, angle, offset):
        img, point, phi = mirrored_image(1, angle, offset)
        level, (sx, sy) = band_level(img[None], 128, 4.0)
        peaks_angle, peaks_centre, ncc = map_peaks(mirror_map(level.mean(0, keepdim=True)), 1)
        centre = (peaks_centre[0] + 0.5) / torch.tensor([sx, sy]) - 0.5  # back to image pixels
        da, dist = _line_error(float(peaks_angle[0]), centre, point, phi)
        assert da < 1.0 and dist < 1.5 and float(ncc[0]) > 0.8

    def test_axis_correlation_peaks_on_the_axis(self):
        img, point, phi = mirrored_image(2, 60.0, 8.0)
        level, (sx, sy) = band_level(img[None], 128, 4.0)
        mmap = mirror_map(level.mean(0, keepdim=True))
        on = (point + 0.5) * torch.tensor([sx, sy]) - 0.5
        n = torch.tensor([-math.sin(phi), math.cos(phi)])
        centres = torch.stack([on, on + 10 * n])
        angles = torch.tensor([phi, phi + math.pi])  # the same line both ways, then a line 10 px off
        v = axis_correlation(mmap, AxisParams(centres, angles[:2], torch.ones(2), torch.ones(2)))
        assert float(v[0]) > 0.8 and float(v[1]) < float(v[0]) - 0.2
        same = axis_correlation(mmap, AxisParams(on[None].repeat(2, 1), angles, torch.ones(2), torch.ones(2)))
        assert abs(float(same[0] - same[1])) < 1e-4

    def test_noise_correlates_little(self):
        level, _ = band_level(torch.rand(1, 3, 180, 240, generator=torch.Generator().manual_seed(5)), 128, 4.0)
        mmap = mirror_map(level.mean(0, keepdim=True))
        assert float(mmap.ncc.max()) < 0.5

    def test_time(self):
        img, _, _ = mirrored_image(3, 45.0, 0.0, 480, 640)
        torch.set_num_threads(1)
        t = time.perf_counter()
        level, _ = band_level(img[None], 128, 4.0)
        map_peaks(mirror_map(level.mean(0, keepdim=True)), 3)
        assert time.perf_counter() - t < 2.0  # the target is 0.3 s on a quiet core; a shared machine gets slack


class TestStageUsesRegistration:
    def test_mirrored_photo_axis_found(self):
        img, point, phi = mirrored_image(4, 75.0, 12.0)
        res = image_axes(img)
        assert res.info["n_registration"] == AxisStageSettings().registration.count
        seg = res.axes[0]
        angle = math.atan2(float(seg[3] - seg[1]), float(seg[2] - seg[0]))
        da, dist = _line_error(angle, (seg[:2] + seg[2:]) / 2, point, phi)
        assert da < 3.0 and dist < 4.0
        assert len(res.info["registration"]) == len(res)

    def test_off_when_neither_axes_nor_weight(self):
        img, _, _ = mirrored_image(5, 30.0, 0.0)
        res = image_axes(img, registration={"count": 0})
        assert res.info["n_registration"] == 0 and res.info["stage_seconds"]["registration"] < 0.01
        assert all(v == 0.0 for v in res.info["registration"])
