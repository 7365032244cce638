"""Candidate axes from mirror pairs, their runs along a line, and the mirrored-SIFT candidates
of method (b) (torchsym.image.candidates)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from torchsym.errors import ConfigError, InputShapeError, InputValueError
from torchsym.image import boundary_clique_axes, ksymmetry_axes
from torchsym.image.candidates import mirror_pair_candidates, support_runs
from torchsym.image.evidence import _grow, axis_evidence, mirror_gradients
from torchsym.image.synthetic import mirrored_objects_image
from torchsym.metrics.axes import match_axes


def _pairs_about(line: np.ndarray, ts, half: float = 20.0, around=(0.0, 0.0)) -> np.ndarray:
    """Exact mirror pairs about ``line`` with half chord ``half``, midpoints at ``ts`` along the
    line from the foot of ``around`` on it (the origin's foot by default)."""
    a, b, c = line
    n, d = np.array([a, b]), np.array([-b, a])
    foot = np.asarray(around, dtype=np.float64) - (n @ np.asarray(around, dtype=np.float64) + c) * n
    mid = foot + np.asarray(ts, dtype=np.float64)[:, None] * d
    return np.concatenate([mid - half * n, mid + half * n], 1)


def _line(angle_deg: float, through) -> np.ndarray:
    """Line whose normal is at ``angle_deg``, through the point ``through``."""
    n = np.array([math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))])
    return np.array([n[0], n[1], -n @ np.asarray(through, dtype=np.float64)])


def _angle(l1: np.ndarray, l2: np.ndarray) -> float:
    return math.degrees(math.acos(min(1.0, abs(float(l1[:2] @ l2[:2])))))


def _recounted_candidates(pairs: np.ndarray, height: int, width: int, min_support: int):
    """The greedy inlier counting of mirror_pair_candidates, every count taken afresh each round."""
    from torchsym.image.candidates import GATHER_ANGLE, GATHER_DISTANCE, pixel_inliers
    from torchsym.image.lines import fit_axis

    chord = pairs[:, 2:] - pairs[:, :2]
    normal = chord / np.linalg.norm(chord, axis=1, keepdims=True)
    mid = 0.5 * (pairs[:, :2] + pairs[:, 2:])
    tol = GATHER_DISTANCE * max(height, width)
    inl = pixel_inliers(pairs, np.concatenate([normal, -(normal * mid).sum(1, keepdims=True)], 1), GATHER_ANGLE, tol)
    centre, scale = np.array([(width - 1) / 2, (height - 1) / 2]), max(height, width) / 2.0
    free, out = np.ones(pairs.shape[0], dtype=bool), []
    while len(out) < 30:
        counts = np.where(free, inl[free].sum(0), -1)  # recounted every round
        if counts.max() < min_support:
            return out
        j = int(counts.argmax())
        line = fit_axis(pairs[inl[:, j] & free], centre, scale)
        members = np.flatnonzero(free & (pixel_inliers(pairs, line[None], GATHER_ANGLE, tol)[:, 0] | inl[:, j]))
        free[members], free[j] = False, False
        out.append((line, members))
    return out


class TestSupportRuns:
    def test_split_at_gaps_in_order(self):
        line = _line(30.0, (100, 100))
        pairs = _pairs_about(line, [40, 0, 10, 100, 5, 108])  # runs {0, 5, 10}, {40}, {100, 108}
        runs = support_runs(line, pairs, np.arange(6), gap=20.0)
        assert [r.tolist() for r in runs] == [[1, 4, 2], [0], [3, 5]]
        assert support_runs(line, pairs, np.arange(6), gap=100.0)[0].size == 6
        assert support_runs(line, pairs, np.array([3, 0]), gap=20.0)[0].tolist() == [0]
        assert support_runs(line, pairs, np.zeros(0, np.int64), gap=20.0) == []


class TestMirrorPairCandidates:
    def test_two_axes_among_clutter(self):
        """A big and a small set of exact pairs among random pairs: both axes come out, big first."""
        rng = np.random.default_rng(0)
        big, small = _line(25.0, (150, 120)), _line(100.0, (400, 300))
        pairs = np.concatenate([
            _pairs_about(big, np.linspace(-60, 60, 12), half=30.0, around=(150, 120)),
            _pairs_about(small, np.linspace(-15, 15, 5), half=12.0, around=(400, 300)) + rng.normal(0, 0.3, (5, 4)),
            rng.uniform(0, 480, (150, 4)),
        ])
        cands = mirror_pair_candidates(pairs, 480, 640)
        assert len(cands) >= 2
        line0, members0 = cands[0]
        assert _angle(line0, big) < 0.01 and abs(line0[2] * np.sign(line0[:2] @ big[:2]) - big[2]) < 0.01
        assert set(range(12)) <= set(members0.tolist())
        found = [(ln, m) for ln, m in cands if _angle(ln, small) < 3.0 and abs(np.array([400, 300, 1.0]) @ ln) < 3.0]
        assert found and set(found[0][1].tolist()) >= set(range(12, 17))
        assert cands[0][1].size >= max(m.size for _, m in cands)

    def test_two_objects_on_one_line_are_one_candidate(self):
        """The evidence, not the candidates, decides how far an axis reaches."""
        line = _line(60.0, (300, 200))
        pairs = np.concatenate([_pairs_about(line, np.linspace(-200, -150, 6)), _pairs_about(line, np.linspace(100, 150, 6))])
        whole = mirror_pair_candidates(pairs, 480, 640)
        assert len(whole) == 1 and whole[0][1].tolist() == list(range(12))

    def test_min_support_and_empty(self):
        line = _line(0.0, (100, 100))
        assert mirror_pair_candidates(_pairs_about(line, [0, 5, 10]), 200, 200) == []
        assert len(mirror_pair_candidates(_pairs_about(line, [0, 5, 10]), 200, 200, min_support=3)) == 1
        assert mirror_pair_candidates(np.zeros((0, 4)), 200, 200) == []

    def test_same_candidates_as_recounting(self):
        """The inlier counts kept up to date give the candidates of recounting every round."""
        rng = np.random.default_rng(3)
        lines = [_line(a, (rng.uniform(100, 500), rng.uniform(100, 380))) for a in (10.0, 75.0, 130.0)]
        pairs = np.concatenate([_pairs_about(ln, rng.uniform(-80, 80, 9), half=rng.uniform(10, 60)) for ln in lines]
                               + [rng.uniform(0, 480, (60, 4))])
        pairs[:, :2] += rng.normal(0, 0.5, (pairs.shape[0], 2))
        got = mirror_pair_candidates(pairs, 480, 640, min_support=2)
        assert [m.tolist() for _, m in got] == [m.tolist() for _, m in _recounted_candidates(pairs, 480, 640, 2)]
        assert len(got) >= 3

    @pytest.mark.parametrize(("kw", "name", "err"), [
        ({"pairs": np.zeros((5, 3))}, "pairs", InputShapeError),
        ({"pairs": np.full((5, 4), np.nan)}, "pairs", InputValueError),
        ({"angle_tol": 0.0}, "angle_tol", InputValueError),
        ({"distance_tol": -1.0}, "distance_tol", InputValueError),
        ({"min_support": 0}, "min_support", InputValueError),
        ({"max_candidates": 1.5}, "max_candidates", InputValueError),
    ])
    def test_bad_input(self, kw, name, err):
        args = {"pairs": np.zeros((5, 4)), **kw}
        with pytest.raises(err, match=name):
            mirror_pair_candidates(args.pop("pairs"), 100, 100, **args)


class TestGrowthGap:
    def test_growth_does_not_cross_empty_background(self):
        """A mirrored blob 60 px beyond the object's end, empty between: not joined with max_gap."""
        img = np.zeros((220, 200), np.float32)
        img[40:100, 70:130] = 1.0  # symmetric about x = 99.5
        img[160:170, 90:110] = 1.0  # a stray mirrored blob further down the axis
        line = np.array([1.0, 0.0, -99.5])
        pairs = np.array([[72.0, y, 127.0, y] for y in np.linspace(50, 90, 9)])
        gx, gy = mirror_gradients(img)
        gapped = axis_evidence(gx, gy, line, pairs, noise_level=0.01)  # the smoothing's tails count as empty
        open_ended = axis_evidence(gx, gy, line, pairs, max_gap=None, noise_level=0.01)
        # along x = 99.5 the parameter of clip_line_to_image is y (foot (99.5, 0), direction (0, 1))
        assert gapped.extent[0] == pytest.approx(40, abs=8) and gapped.extent[1] == pytest.approx(100, abs=8)  # a bin + smoothing
        assert open_ended.extent[1] > 160  # without the rule the segment reaches the blob
        with pytest.raises(InputValueError, match="max_gap"):
            axis_evidence(gx, gy, line, pairs, max_gap=-1)


class TestSiftCandidates:
    def test_small_objects_found(self):
        """The synthetic image whose two small objects have no boundary pairs: SIFT pairs find
        them (kornia's SIFT keeps its 1000 strongest keypoints there, OpenCV's default finds
        about 100 above its contrast threshold and one of the two)."""
        img, gt = mirrored_objects_image(3, generator=torch.Generator().manual_seed(1003))
        res = boundary_clique_axes(img, sift={"backend": "kornia"})
        plain = boundary_clique_axes(img, sift={"enabled": False})
        hit = match_axes(res.axes, gt, image_size=(360, 480), scores=res.scores, criterion="challenge")
        hit_plain = match_axes(plain.axes, gt, image_size=(360, 480), scores=plain.scores, criterion="challenge")
        assert int(hit.sum()) >= 2 and int(hit_plain.sum()) < int(hit.sum())
        assert res.info["n_sift_pairs"] > 0 and res.info["sift_axes"] >= 1
        assert res.pairs.shape[0] == res.info["n_pairs_found"] + res.info["n_sift_pairs"]
        assert bool((res.scores[1:] <= res.scores[:-1]).all())

    def test_settings(self):
        img = torch.rand(3, 48, 48)
        with pytest.raises(ConfigError, match="sift.enabled"):
            boundary_clique_axes(img, score="support", sift={"enabled": True})
        with pytest.raises(ConfigError, match="sift.enabled"):
            boundary_clique_axes(img, sift={"enabled": "yes"})
        with pytest.raises(ConfigError, match="sift.weight"):
            boundary_clique_axes(img, sift={"weight": 0.0})
        assert "sift" not in boundary_clique_axes(img, score="support").info["stage_seconds"]
        with pytest.raises(ConfigError, match="sift.backend"):
            boundary_clique_axes(img, sift={"backend": "vlfeat"})
        with pytest.raises(ConfigError, match="sift.min_support"):
            boundary_clique_axes(img, sift={"min_support": 0})

    def test_min_support(self):
        """A planted object with three mirrored-SIFT pairs on its axis (seed 1011, OpenCV's
        SIFT) is a candidate from ``sift.min_support`` 3 on, not at 4."""
        img, gt = mirrored_objects_image(3, generator=torch.Generator().manual_seed(1011))
        found = {}
        for k in (3, 4):
            res = boundary_clique_axes(img, sift={"min_support": k})
            found[k] = bool(match_axes(res.axes, gt[2:], image_size=(360, 480), criterion="challenge").any())
        assert found == {3: True, 4: False}


class TestKSymmetryGradientScore:
    def test_segments_on_the_objects(self):
        """Clustered axes spread along their lines; the gradient score's segments sit on the objects."""
        img, gt = mirrored_objects_image(3, generator=torch.Generator().manual_seed(1009))
        kornia = {"backend": "kornia"}  # its 1000 keypoints; OpenCV's default finds few on synthetic images
        res = ksymmetry_axes(img, score="gradient", max_axes=8, pairs=kornia)
        thesis = ksymmetry_axes(img, max_axes=8, score="support", pairs=kornia)
        hit = match_axes(res.axes, gt, image_size=(360, 480), scores=res.scores, criterion="challenge")
        hit_thesis = match_axes(thesis.axes, gt, image_size=(360, 480), scores=thesis.scores, criterion="challenge")
        assert int(hit.sum()) > int(hit_thesis.sum())
        assert "axes_without_evidence" in res.info and "axes_without_evidence" not in thesis.info

    def test_bad_score(self):
        with pytest.raises(ConfigError, match="score"):
            ksymmetry_axes(torch.rand(1, 32, 32), score="votes")
        with pytest.raises(ConfigError, match="grow_threshold"):
            ksymmetry_axes(torch.rand(1, 32, 32), score="gradient", grow_threshold=3.0)


class TestReviewedEdges:
    """Cases a mutation review found unpinned."""

    def test_grow_best_run(self):
        t = np.arange(6) * 4.0 + 1.0  # one sample per 4-px bin, bins 0..5
        assert _grow(t, np.array([1.0, 1.0, -3.0, 0.0, 0.0, 5.0]), 4.0) == 24.0  # the run to bin 5 gains most
        assert _grow(t, np.array([1.0, 1.0, -9.0, 0.0, 0.0, 5.0]), 4.0) == 8.0
        assert _grow(t, -np.ones(6), 4.0) == 0.0 and _grow(np.zeros(0), np.zeros(0), 4.0) == 0.0

    def test_grow_gap_boundaries(self):
        t = np.arange(6) * 4.0 + 1.0  # one sample per 4-px bin, bins 0..5
        gain = np.array([1.0, 1.0, 0.0, 0.0, 0.0, 5.0])
        strong = gain != 0
        assert _grow(t, gain, 4.0, strong, 2) == 8.0  # bins 2-4 empty: 3 > max_gap, stop before them
        assert _grow(t, gain, 4.0, strong, 3) == 24.0  # a gap of 3 is allowed: reach bin 5
        assert _grow(t, gain, 4.0, strong, None) == 24.0
        first_empty = np.array([0.0, 2.0])
        assert _grow(np.array([1.0, 5.0]), first_empty, 4.0, first_empty != 0, 0) == 0.0  # gap at bin 0
        assert _grow(np.array([1.0, 5.0]), first_empty, 4.0, first_empty != 0, 1) == 8.0
        assert _grow(t, gain, 4.0, strong, 10**9) == 24.0  # a huge max_gap allocates nothing large

    def test_support_runs_bad_input(self):
        line = _line(0.0, (100, 100))
        pairs = _pairs_about(line, [0, 5])
        with pytest.raises(InputValueError, match="members"):
            support_runs(line, pairs, np.array([0, 7]), gap=10.0)
        with pytest.raises(InputShapeError, match="pairs"):
            support_runs(line, pairs[:, :3], np.array([0]), gap=10.0)
        with pytest.raises(InputValueError, match="gap"):
            support_runs(line, pairs, np.array([0]), gap=-1.0)

    def test_candidate_is_refitted(self):
        """Two parallel objects 2 px apart (within the tolerance): one candidate, fitted between them."""
        a, b = _line(0.0, (100, 100)), _line(0.0, (102, 100))
        pairs = np.concatenate([_pairs_about(a, np.linspace(-200, -150, 6)), _pairs_about(b, np.linspace(100, 150, 6))])
        cands = mirror_pair_candidates(pairs, 480, 640)
        assert len(cands) == 1 and cands[0][1].tolist() == list(range(12))
        mid = 0.5 * (pairs[:, :2] + pairs[:, 2:])
        assert np.abs(mid @ cands[0][0][:2] + cands[0][0][2]).max() < 1.0 + 1e-6
        with pytest.raises(InputValueError, match="height"):
            mirror_pair_candidates(pairs, 0, 640)

    def test_sift_axes_index_their_own_pairs(self):
        img, _ = mirrored_objects_image(3, generator=torch.Generator().manual_seed(1003))
        res = boundary_clique_axes(img)
        n_bnd = res.info["n_pairs_found"]
        sift_axes = 0
        for k in range(len(res)):
            idx = torch.nonzero(res.pair_axis == k).flatten()
            pts = res.pairs[idx].double()
            mid = 0.5 * (pts[:, :2] + pts[:, 2:])
            assert float((mid @ res.lines[k, :2].double() + res.lines[k, 2]).abs().max()) < 10.0  # on its own line
            sift_axes += bool((idx >= n_bnd).all())
        assert sift_axes >= 1
        half = boundary_clique_axes(img, sift={"weight": 0.25})
        full = {tuple(ln): s for ln, s in zip(res.lines.tolist(), res.scores.tolist())}
        scaled = [(s, full[tuple(ln)]) for ln, s, k in zip(half.lines.tolist(), half.scores.tolist(), range(len(half)))
                  if tuple(ln) in full and bool((half.pair_axis == k).any()) and
                  bool((torch.nonzero(half.pair_axis == k).flatten() >= n_bnd).all())]
        assert scaled and all(s == pytest.approx(0.5 * f, rel=1e-5) for s, f in scaled)  # 0.25 / 0.5

    def test_sift_axes_without_enough_boundary_pairs(self):
        img, gt = mirrored_objects_image(1, height=240, width=240, generator=torch.Generator().manual_seed(0))
        res = boundary_clique_axes(img, cliques={"min_support": 10**5})  # no clique can reach this
        assert len(res) >= 1 and res.info["sift_axes"] >= 1
        assert bool(match_axes(res.axes[:2], gt, image_size=(240, 240), criterion="challenge").any())
        assert len(boundary_clique_axes(img, cliques={"min_support": 10**5}, sift={"enabled": False})) == 0
