"""Dense mirror-gradient evidence of an axis: its score and extent (torchsym.image.evidence)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
import torch

from torchsym.errors import ConfigError, InputShapeError, InputValueError
from torchsym.image import boundary_clique_axes
from torchsym.image.evidence import EDGE_NOISE, _bilinear, axis_evidence, gradient_noise, mirror_gradients
from torchsym.image.lines import clip_line_to_image


def _rotation(angle: float, centre=(100.0, 100.0)) -> np.ndarray:
    """2 x 3 affine map rotating by ``angle`` degrees about ``centre``."""
    th = math.radians(angle)
    r = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    return np.concatenate([r, (np.asarray(centre) - r @ np.asarray(centre))[:, None]], 1)


def _kite(angle: float = 0.0, noise: float = 0.02, size: int = 200) -> tuple[np.ndarray, np.ndarray]:
    """A kite symmetric about its axis from ``(100, 40)`` (tip) to ``(100, 160)``, turned by ``angle`` deg.

    Returns the grey image (seeded noise) and the 2 x 3 rotation.
    """
    m = _rotation(angle)
    poly = np.array([[100, 40], [135, 90], [100, 160], [65, 90]], np.float64)
    poly = poly @ m[:, :2].T + m[:, 2]
    img = np.full((size, size), 0.2, np.float32)
    cv2.fillPoly(img, [np.round(poly * 16).astype(np.int32)], 0.8, cv2.LINE_AA, shift=4)
    return img + noise * np.random.default_rng(0).standard_normal(img.shape).astype(np.float32), m


def _kite_axis_and_pairs(m: np.ndarray, y0: float = 100.0, y1: float = 130.0):
    """The kite's axis (unit normal) and 9 mirror pairs on its lower edges between rows y0 and y1 (before turning)."""
    y = np.linspace(y0, y1, 9)
    half = 35.0 * (160.0 - y) / 70.0
    left = np.stack([100 - half, y], 1) @ m[:, :2].T + m[:, 2]
    right = np.stack([100 + half, y], 1) @ m[:, :2].T + m[:, 2]
    n = m[:, :2] @ np.array([1.0, 0.0])
    centre = m[:, :2] @ np.array([100.0, 100.0]) + m[:, 2]
    return np.array([n[0], n[1], -n @ centre]), np.concatenate([left, right], 1)


def _t(line: np.ndarray, point) -> float:
    """Parameter of ``point`` along ``line`` (as in clip_line_to_image)."""
    a, b, c = line
    return float((np.asarray(point, dtype=np.float64) - np.array([-c * a, -c * b])) @ np.array([-b, a]))


class TestAxisEvidence:
    @pytest.mark.parametrize("angle", [0.0, 35.0, 90.0, 200.0])
    def test_extent_grows_to_the_object(self, angle):
        """Pairs on the middle third only; the extent grows to the tip and the bottom, within a bin."""
        img, m = _kite(angle)
        line, pairs = _kite_axis_and_pairs(m)
        gx, gy = mirror_gradients(img)
        ev = axis_evidence(gx, gy, line, pairs, noise_level=EDGE_NOISE * gradient_noise(gx, gy))  # as the detectors set it
        tip = m[:, :2] @ np.array([100.0, 40.0]) + m[:, 2]
        bottom = m[:, :2] @ np.array([100.0, 160.0]) + m[:, 2]
        ends = sorted((_t(line, tip), _t(line, bottom)))
        assert ev.extent[0] == pytest.approx(ends[0], abs=5) and ev.extent[1] == pytest.approx(ends[1], abs=5)
        assert ev.symmetry > 0.9
        assert ev.to_dict()["extent"] == pytest.approx(list(ev.extent))  # JSON-ready like every result
        plain = axis_evidence(*mirror_gradients(img), line, pairs, grow_threshold=None)
        t_pairs = sorted((_t(line, pairs[0, :2]), _t(line, pairs[-1, :2])))
        assert plain.extent == pytest.approx(tuple(t_pairs), abs=1e-6)

    def test_area_is_the_band(self):
        """Band of half-width 30.6 (90th percentile half chord) less the 4 px gap, 30 px long, step 2."""
        img, m = _kite()
        line, pairs = _kite_axis_and_pairs(m)
        ev = axis_evidence(*mirror_gradients(img), line, pairs)
        half = np.percentile(0.5 * np.hypot(*(pairs[:, 2:] - pairs[:, :2]).T), 90)
        rows = len(np.arange(4.0, half + 1e-9, 2.0)) * 2
        assert ev.area == pytest.approx(16 * rows * 4.0 / 200**2)  # 16 samples over t in [100, 130]

    def test_wrong_axis_has_less_symmetry(self):
        img, m = _kite()
        line, pairs = _kite_axis_and_pairs(m)
        gx, gy = mirror_gradients(img)
        true = axis_evidence(gx, gy, line, pairs).symmetry
        th = math.radians(10)
        tilted = np.array([math.cos(th), math.sin(th), 0.0])
        tilted[2] = -(tilted[:2] @ np.array([100.0, 115.0]))  # through the same centre
        assert axis_evidence(gx, gy, tilted, pairs).symmetry < true - 0.4
        shifted = line - np.array([0.0, 0.0, 6.0])  # 6 px to the side
        assert axis_evidence(gx, gy, shifted, pairs).symmetry < true - 0.3

    def test_noise_has_no_evidence(self):
        gray = np.random.default_rng(1).random((200, 200)).astype(np.float32)
        line, pairs = _kite_axis_and_pairs(_rotation(0.0))
        ev = axis_evidence(*mirror_gradients(gray), line, pairs)
        assert abs(ev.symmetry) < 0.15
        assert ev.extent[1] - ev.extent[0] < 30 + 2 * 8  # at most a couple of bins of chance growth

    def test_extent_stops_at_clutter(self):
        img, m = _kite()
        img[:70] = np.random.default_rng(2).random((70, 200))  # unsymmetric texture over the tip
        line, pairs = _kite_axis_and_pairs(m)
        lo, hi = axis_evidence(*mirror_gradients(img), line, pairs).extent
        assert 62 <= lo <= 80 and hi == pytest.approx(160, abs=5)

    def test_bad_input(self):
        gx, gy = mirror_gradients(np.zeros((20, 20), np.float32))
        line = np.array([1.0, 0.0, -10.0])
        pair = np.array([[5.0, 10.0, 15.0, 10.0]])
        with pytest.raises(InputValueError, match="pairs"):
            axis_evidence(gx, gy, line, np.zeros((0, 4)))
        with pytest.raises(InputValueError, match="pairs"):
            axis_evidence(gx, gy, line, np.full((1, 4), np.nan))
        with pytest.raises(InputShapeError, match="pairs"):
            axis_evidence(gx, gy, line, np.zeros((3, 2)))
        with pytest.raises(InputValueError, match="line"):
            axis_evidence(gx, gy, np.array([0.0, 0.0, 1.0]), pair)
        with pytest.raises(InputShapeError, match="line"):
            axis_evidence(gx, gy, np.ones(4), pair)
        with pytest.raises(InputShapeError, match="gx"):
            axis_evidence(gx, gy[:5], line, pair)
        with pytest.raises(InputValueError, match="grow_threshold"):
            axis_evidence(gx, gy, line, pair, grow_threshold=1.5)
        blank = axis_evidence(gx, gy, line, pair)
        assert blank.symmetry == 0.0 and blank.extent == (10.0, 10.0)
        off = axis_evidence(gx, gy, np.array([1.0, 0.0, 100.0]), pair)  # x = -100: misses the image
        assert off.area == 0.0 and off.symmetry == 0.0


class TestExtentRules:
    """The extent's guard: the image's noise level."""

    @staticmethod
    def _faint_kite_on_shading(contrast: float = 0.1) -> np.ndarray:
        """A faint kite on a noisy brightness ramp along its axis (shading that is its own mirror image)."""
        yy = np.arange(200, dtype=np.float32)[:, None].repeat(200, 1)
        img = 0.3 + 0.002 * (yy - 100)
        mask = np.zeros((200, 200), np.float32)
        poly = np.array([[100, 40], [135, 90], [100, 160], [65, 90]], np.float64)
        cv2.fillPoly(mask, [np.round(poly * 16).astype(np.int32)], 1.0, cv2.LINE_AA, shift=4)
        return img + contrast * mask + 0.02 * np.random.default_rng(0).standard_normal(img.shape).astype(np.float32)

    def test_noise_level_stops_growth_in_shading(self):
        gx, gy = mirror_gradients(self._faint_kite_on_shading())
        line, pairs = _kite_axis_and_pairs(_rotation(0.0), y0=60.0)
        lo, hi = axis_evidence(gx, gy, line, pairs, noise_level=EDGE_NOISE * gradient_noise(gx, gy)).extent
        assert lo == pytest.approx(40, abs=5) and hi == pytest.approx(160, abs=5)
        lo, hi = axis_evidence(gx, gy, line, pairs).extent  # relative rule alone: noise counts as edges
        assert lo < 10 and hi > 190

    def test_gradient_noise(self):
        flat = np.zeros((30, 40), np.float32)
        assert gradient_noise(flat, flat) == 0.0
        gx, gy = mirror_gradients(np.random.default_rng(3).random((64, 64)).astype(np.float32))
        assert gradient_noise(gx, gy) == pytest.approx(float(np.median(np.hypot(gx, gy))))
        assert gradient_noise(gx, gy) > 0

    def test_bad_settings(self):
        gx, gy = mirror_gradients(np.zeros((20, 20), np.float32))
        line, pair = np.array([1.0, 0.0, -10.0]), np.array([[5.0, 10.0, 15.0, 10.0]])
        with pytest.raises(InputValueError, match="noise_level"):
            axis_evidence(gx, gy, line, pair, noise_level=-1.0)
        with pytest.raises(InputShapeError, match="gx, gy"):
            gradient_noise(gx, gy[:5])


class TestScores:
    def test_support_scores_count_pairs(self, single_objects):
        """The thesis's ranking: an axis's share of the image's symmetric boundary pairs."""
        img, _ = single_objects[0]
        res = boundary_clique_axes(img, score="support")
        counts = torch.tensor([float((res.pair_axis == k).sum()) for k in range(len(res))])
        assert torch.allclose(res.scores, counts / res.pairs.shape[0])

    def test_segments_are_the_grown_extents(self, single_objects):
        """Each axis is its line clipped to the extent axis_evidence reports, and the score is built from it."""
        img, _ = single_objects[0]
        res = boundary_clique_axes(img, sift={"enabled": False})
        plain = boundary_clique_axes(img, grow_threshold=None, sift={"enabled": False})
        assert torch.equal(res.lines, plain.lines) and len(res) >= 2
        gx, gy = mirror_gradients(img.mean(0).numpy())
        noise = EDGE_NOISE * gradient_noise(gx, gy)  # the image's noise level, as the detector sets it
        longer = 0
        for k in range(len(res)):
            sup = res.pairs[res.pair_axis == k].double().numpy()
            ev = axis_evidence(gx, gy, res.lines[k].double().numpy(), sup, min_half_width=8.0, noise_level=noise)
            seg = clip_line_to_image(res.lines[k].double(), *ev.extent, 240, 240)
            assert res.axes[k].tolist() == pytest.approx(seg, abs=1e-3)
            score = max(ev.symmetry, 0.0) * math.sqrt(ev.area)
            assert float(res.scores[k]) == pytest.approx(score, rel=1e-4)
            longer += float((res.axes[k, 2:] - res.axes[k, :2]).norm()) > float((plain.axes[k, 2:] - plain.axes[k, :2]).norm()) + 1
        assert longer >= 1

    def test_axes_without_evidence_are_dropped(self, single_objects):
        img, _ = single_objects[0]
        res = boundary_clique_axes(img, sift={"enabled": False})
        every = boundary_clique_axes(img, score="support")
        assert bool((res.scores > 0).all())
        assert len(res) + res.info["axes_without_evidence"] == len(every)
        assert res.info["axes_without_evidence"] >= 1  # this image has a clique on clutter
        kept = {tuple(v) for v in res.lines.tolist()}
        assert kept < {tuple(v) for v in every.lines.tolist()}

    @pytest.mark.parametrize(("kw", "name"), [({"score": "votes"}, "score"), ({"grow_threshold": 2.0}, "grow_threshold"),
                                              ({"grow_threshold": True}, "grow_threshold")])
    def test_bad_settings(self, kw, name):
        with pytest.raises(ConfigError, match=name):
            boundary_clique_axes(torch.rand(3, 32, 32), **kw)


class TestBilinear:
    def test_matches_scipy(self):
        """OpenCV's remap gives scipy's bilinear values (within its 1/32-px weights) and NaN
        at the same points outside the image; more points than remap's 32767-row limit."""
        from scipy.ndimage import map_coordinates

        rng = np.random.default_rng(0)
        img = cv2.GaussianBlur(rng.random((60, 80)).astype(np.float32), (0, 0), 2.0)
        x, y = rng.uniform(-3, 83, 40000), rng.uniform(-3, 63, 40000)
        ref = map_coordinates(img, np.stack([y, x]), order=1, mode="constant", cval=np.nan, prefilter=False)
        got = _bilinear(img, x, y)
        assert got.shape == (40000,)
        assert np.array_equal(np.isnan(got), np.isnan(ref)) and np.isnan(got).any()
        ok = ~np.isnan(ref)
        assert np.abs(got[ok] - ref[ok]).max() < 2e-3
        assert _bilinear(img, np.zeros(0), np.zeros(0)).shape == (0,)
