"""Dense mirror-gradient evidence of an axis: its score and extent (torchsym.image.evidence)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
import torch

from torchsym.errors import ConfigError, InputShapeError, InputValueError
from torchsym.image import boundary_clique_axes
from torchsym.image.evidence import EDGE_NOISE, axis_evidence, gradient_noise, mirror_gradients
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
        ev = axis_evidence(*mirror_gradients(img), line, pairs)
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


def _moved(points: np.ndarray, m: np.ndarray) -> np.ndarray:
    """``(M, 4)`` pairs given before turning, turned by the 2 x 3 map ``m``."""
    p = points.reshape(-1, 2) @ m[:, :2].T + m[:, 2]
    return p.reshape(-1, 4)


class TestExtentRules:
    """The extent's guards: pairs along the axis, the noise level, edge crossings."""

    @pytest.mark.parametrize("angle", [0.0, 35.0])
    def test_pairs_along_the_axis_stretch_only_nearby(self, angle):
        """Points on the line stretch the mirror pairs' extent in steps of at most along_gap x 200 px."""
        img, m = _kite(angle)
        line, pairs = _kite_axis_and_pairs(m)  # mirror pairs on rows 100..130
        along = _moved(np.array([[100.0, 135.0, 100.0, 190.0], [100.0, 92.0, 100.0, 15.0]]), m)  # chords on the axis
        at = {y: _t(line, _moved(np.array([[100.0, y, 0.0, 0.0]]), m)[0, :2]) for y in (15.0, 92.0, 135.0, 190.0)}
        gx, gy = mirror_gradients(img)
        every = np.concatenate([pairs, along])
        # default along_gap 0.1 x 200 = 20 px: 135 (5 px on) and 92 (8 px) count, 190 and 15 are too far
        ends = sorted(axis_evidence(gx, gy, line, every, grow_threshold=None).extent)
        assert ends == pytest.approx(sorted((at[92.0], at[135.0])), abs=1e-6)
        old = sorted(axis_evidence(gx, gy, line, every, grow_threshold=None, along_gap=None).extent)
        assert old == pytest.approx(sorted((at[15.0], at[190.0])), abs=1e-6)
        only_along = sorted(axis_evidence(gx, gy, line, along, grow_threshold=None).extent)  # no mirror pair: every point
        assert only_along == pytest.approx(old, abs=1e-6)

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

    @pytest.mark.parametrize("angle", [0.0, 35.0])
    def test_crossings_trim_a_stray_pair(self, angle):
        img, m = _kite(angle)
        line, pairs = _kite_axis_and_pairs(m)
        stray = _moved(np.array([[90.0, 185.0, 110.0, 185.0]]), m)  # mirrored, but beyond the kite
        every = np.concatenate([pairs, stray])
        gx, gy = mirror_gradients(img)
        tip, bottom, beyond = (_t(line, _moved(np.array([[100.0, y, 0, 0]]), m)[0, :2]) for y in (40.0, 160.0, 185.0))
        ends = sorted(axis_evidence(gx, gy, line, every, crossings=True).extent)
        assert ends == pytest.approx(sorted((tip, bottom)), abs=5)
        plain = sorted(axis_evidence(gx, gy, line, every).extent)
        assert plain[0] == pytest.approx(min(tip, beyond), abs=5) and plain[1] == pytest.approx(max(tip, beyond), abs=5)

    def test_crossings_keep_the_extent_when_most_pairs_lie_outside(self):
        """Pairs on rows 150..195: the only crossing is near the kite's bottom; trimming to it would drop 6 of 10 midpoints."""
        img, _ = _kite()
        y = np.linspace(150.0, 195.0, 10)
        pairs = np.stack([np.full(10, 90.0), y, np.full(10, 110.0), y], 1)
        line = np.array([1.0, 0.0, -100.0])
        gx, gy = mirror_gradients(img)
        noise = EDGE_NOISE * gradient_noise(gx, gy)  # else the background's noise crosses the line everywhere
        kept = axis_evidence(gx, gy, line, pairs, crossings=True, noise_level=noise).extent
        assert kept == axis_evidence(gx, gy, line, pairs, noise_level=noise).extent and kept[1] == pytest.approx(195.0)
        few = pairs[:3]  # rows 150..160, all at the crossing: trimmed to it, where the growth went up the kite
        grown = axis_evidence(gx, gy, line, few, noise_level=noise).extent
        trimmed = axis_evidence(gx, gy, line, few, crossings=True, noise_level=noise).extent
        assert grown[0] < 140 and 148 <= trimmed[0] <= 156 and trimmed[1] == pytest.approx(160, abs=3)
        blank = np.zeros_like(gx)
        assert axis_evidence(blank, blank, line, pairs, crossings=True).extent == pytest.approx((150.0, 195.0))

    def test_support_split_at_empty_background(self):
        """Pairs on two diamonds on one line, 70 px of background apart: the evidence is the better-supported one's."""
        img = np.full((300, 200), 0.2, np.float32)
        for poly in ([[100, 20], [130, 50], [100, 110], [70, 50]], [[100, 180], [125, 210], [100, 260], [75, 210]]):
            cv2.fillPoly(img, [np.round(np.array(poly, np.float64) * 16).astype(np.int32)], 0.8, cv2.LINE_AA, shift=4)
        img += 0.02 * np.random.default_rng(0).standard_normal(img.shape).astype(np.float32)

        def edge_pairs(y0, y1, k, wide_y, half_w, bottom):  # mirror pairs on a diamond's lower edges
            y = np.linspace(y0, y1, k)
            h = half_w * (bottom - y) / (bottom - wide_y)
            return np.stack([100 - h, y, 100 + h, y], 1)

        pairs = np.concatenate([edge_pairs(60, 100, 9, 50, 30, 110), edge_pairs(215, 250, 4, 210, 25, 260)])
        line = np.array([1.0, 0.0, -100.0])
        gx, gy = mirror_gradients(img)
        noise = EDGE_NOISE * gradient_noise(gx, gy)
        split = axis_evidence(gx, gy, line, pairs, noise_level=noise)
        assert split.extent == pytest.approx((20, 110), abs=5)
        first = axis_evidence(gx, gy, line, pairs[:9], noise_level=noise)  # exactly the first diamond's
        assert (split.symmetry, split.area, split.extent) == (first.symmetry, first.area, first.extent)
        assert split.kept == tuple(range(9)) and first.kept is None
        whole = axis_evidence(gx, gy, line, pairs, noise_level=noise, split_gap=None)
        assert whole.extent == pytest.approx((20, 260), abs=5) and whole.area > 3 * split.area and whole.kept is None
        assert axis_evidence(gx, gy, line, pairs, noise_level=noise, split_gap=30).extent == whole.extent  # gap ~17 bins
        with pytest.raises(InputValueError, match="split_gap"):
            axis_evidence(gx, gy, line, pairs, split_gap=-1)

    def test_crossings_never_invert_the_extent(self):
        """Crossings only within the search slack beyond the lower end: the extent is kept, not inverted."""
        img, _ = _kite()
        gx, gy = mirror_gradients(img)
        rows = np.array([164.0, 165.0, 166.0, 190.0])
        pairs = np.stack([np.full(4, 95.0), rows, np.full(4, 105.0), rows], 1)
        lo, hi = axis_evidence(gx, gy, np.array([1.0, 0.0, -100.0]), pairs, crossings=True, grow_threshold=1.0,
                               split_gap=None, noise_level=0.05).extent
        assert lo < hi and (lo, hi) == pytest.approx((164.0, 190.0))

    def test_gradient_noise(self):
        flat = np.zeros((30, 40), np.float32)
        assert gradient_noise(flat, flat) == 0.0
        gx, gy = mirror_gradients(np.random.default_rng(3).random((64, 64)).astype(np.float32))
        assert gradient_noise(gx, gy) == pytest.approx(float(np.median(np.hypot(gx, gy))))
        assert gradient_noise(gx, gy) > 0

    def test_bad_settings(self):
        gx, gy = mirror_gradients(np.zeros((20, 20), np.float32))
        line, pair = np.array([1.0, 0.0, -10.0]), np.array([[5.0, 10.0, 15.0, 10.0]])
        with pytest.raises(InputValueError, match="chord_angle"):
            axis_evidence(gx, gy, line, pair, chord_angle=120.0)
        with pytest.raises(InputValueError, match="along_gap"):
            axis_evidence(gx, gy, line, pair, along_gap=-0.1)
        with pytest.raises(InputValueError, match="noise_level"):
            axis_evidence(gx, gy, line, pair, noise_level=-1.0)
        with pytest.raises(InputValueError, match="crossings"):
            axis_evidence(gx, gy, line, pair, crossings="no")
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
