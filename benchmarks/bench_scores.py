"""Score calibration of every registered solver: symmetric against asymmetric inputs (issue 31).

Each solver runs through :func:`torchsym.detect` (its default settings) on a few small,
seeded inputs of its kind, built in code:

- symmetric: planted symmetries (:func:`torchsym.pointset.make_symmetric_pointset`, mirror
  completion of sampled mesh surfaces :func:`torchsym.pointcloud.synthetic.mirror_complete`,
  the shipped chair, :func:`torchsym.image.synthetic.mirrored_texture_image` and
  :func:`~torchsym.image.synthetic.mirrored_objects_image`);
- asymmetric: mixtures of five random Gaussians, random point sets in high dimension, the
  Stanford bunny (``/work/shared/data/meshes/bunny00.off``, surface-sampled; skipped when the
  shared data is missing), uniform noise and smoothed-noise images.

A solver's score is its result's ``score``; for image-axis results (``scores``, one per axis,
best first) the best axis's score, 0 when no axis was found. For each solver: the median
score on symmetric and on asymmetric inputs, the largest asymmetric score, and the ROC AUC of
the score as a symmetric/asymmetric classifier (the probability that a symmetric input scores
above an asymmetric one, ties counting half). Solvers without a scalar score, and
``multiview_plane`` (minutes per scene), are listed without figures, with the reason.
Writes ``benchmarks/results/scores.md`` and ``scores.json``.

``--no-symmetry`` runs the detectors on inputs without symmetry only, more of them and of
more kinds (issue 50), and reports the share scoring at or above 0.3 (target: < 5 % for
every detector), per family of inputs: uniform noise, Gaussian-smoothed noise (sigma 2, 4
and 8 px), box-smoothed noise (``avg_pool2d(noise, 9, 1, 4)``), natural textures (the
dev photos shuffled by 40-px blocks; skimage's grass and gravel, random crops) at
240 x 320; 5-Gaussian mixtures, unions of three random ellipsoid surfaces, and randomly
bent mesh surfaces (bunny, cow, armadillo) as clouds; Gaussian point sets and mixtures
in 3 to 20 dimensions. Writes ``scores_no_symmetry.md`` and ``.json``.

    python benchmarks/bench_scores.py [--quick] [--only NAME ...] [--no-symmetry] [--n 10] [--threads 1] [--out benchmarks/results]
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import statistics
import time
from pathlib import Path

import numpy as np
import torch

import torchsym
from torchsym.core.registry import SOLVERS
from torchsym.image.synthetic import mirrored_objects_image, mirrored_texture_image
from torchsym.pointcloud.synthetic import mirror_complete, sample_surface
from torchsym.pointset import make_symmetric_pointset
from report import write_report  # benchmarks/report.py

HERE = Path(__file__).resolve().parent
MESHES = HERE.parent.parent / "shared" / "data" / "meshes"
PHOTOS = HERE.parent.parent / "shared" / "data" / "images" / "reflection_single_dev"
THRESHOLD = 0.3  # a score at or above this claims a symmetry
log = logging.getLogger("bench_scores")

#: registered solvers not run, and why
SKIPPED = {
    "multiview_plane": "not run: minutes per scene (structure from motion), too slow for this benchmark",
    "stylize": "not a detector: it restyles the symmetry map of the previous step",
    "symmetry_map": "no scalar score: SymmetryMapResult holds per-pixel score maps (ssm), not one score",
    "intrinsic_symmetry": "no scalar score: IntrinsicSymmetryResult holds a vertex map, not a score",
}


def _gen(seed: int) -> torch.Generator:
    return torch.Generator().manual_seed(seed)


def gaussian_mixture(n: int, d: int, seed: int) -> torch.Tensor:
    """``(n, d)`` points from five Gaussians with random centres and widths: no symmetry."""
    g = _gen(seed)
    centres = 2.0 * torch.randn(5, d, generator=g, dtype=torch.float64)
    widths = 0.2 + torch.rand(5, d, generator=g, dtype=torch.float64)  # anisotropic
    label = torch.randint(0, 5, (n,), generator=g)
    return (centres[label] + widths[label] * torch.randn(n, d, generator=g, dtype=torch.float64)).float()


def _read_mesh(name: str):
    from torchsym.io.read import read_mesh

    path = MESHES / name
    return read_mesh(path) if path.exists() else None


def cloud_inputs(quick: bool) -> tuple[list, list]:
    sym = [("chair (shipped)", torchsym.data.sample_pointcloud())]
    for k, name in enumerate(["cow.off", "dino.off", "camel.off"][: 1 if quick else 3]):
        mesh = _read_mesh(name)
        if mesh is not None:
            pts = sample_surface(mesh, 4000, generator=_gen(10 + k))
            sym.append((f"{name} mirror-completed", mirror_complete(pts, generator=_gen(20 + k)).points))
    asym = [(f"5-Gaussian mixture #{k}", gaussian_mixture(4000, 3, 30 + k)) for k in range(2 if quick else 3)]
    bunny = _read_mesh("bunny00.off")
    if bunny is not None:
        asym.append(("bunny, 4000 points", sample_surface(bunny, 4000, generator=_gen(40))))
    return sym, asym


def points_inputs(quick: bool) -> tuple[list, list]:
    cases = [(300, 3, 0.0), (300, 3, 1e-4), (100, 10, 0.0), (200, 6, 1e-4)]
    sym = [
        (f"planted n={n} d={d} sigma^2={s2}", make_symmetric_pointset(n, d, s2, generator=_gen(50 + k)).points)
        for k, (n, d, s2) in enumerate(cases[: 2 if quick else 4])
    ]
    asym = [
        (f"Gaussian n={n} d={d}", torch.randn(n, d, generator=_gen(60 + k), dtype=torch.float64))
        for k, (n, d) in enumerate([(50, 300), (64, 64), (100, 10)][: 2 if quick else 3])
    ]
    asym.append(("5-Gaussian mixture n=300 d=3", gaussian_mixture(300, 3, 70).double()))
    return sym, asym


def _smooth(img: torch.Tensor, sigma: float) -> torch.Tensor:
    r = int(3 * sigma)
    k = torch.exp(-torch.arange(-r, r + 1, dtype=torch.float32) ** 2 / (2 * sigma**2))
    k = k / k.sum()
    c = img.shape[0]
    x = torch.nn.functional.pad(img[None], (r, r, r, r), mode="reflect")
    x = torch.nn.functional.conv2d(x, k.view(1, 1, 1, -1).repeat(c, 1, 1, 1), groups=c)
    x = torch.nn.functional.conv2d(x, k.view(1, 1, -1, 1).repeat(c, 1, 1, 1), groups=c)[0]
    return (x - x.min()) / (x.max() - x.min())


def image_inputs(quick: bool) -> tuple[list, list]:
    n = 2 if quick else 8
    sym = [(f"mirrored texture #{k}", mirrored_texture_image(height=160, width=200, generator=_gen(80 + k))[0]) for k in range(n)]
    sym += [(f"mirrored object #{k}", mirrored_objects_image(1, height=160, width=200, generator=_gen(90 + k))[0])
            for k in range(n)]
    asym = [(f"uniform noise 128 px #{k}", torch.rand(3, 128, 128, generator=_gen(1100 + k))) for k in range(n)]
    asym += [(f"smoothed noise sigma {2 + 2 * (k % 2)} #{k}", _smooth(torch.rand(3, 160, 200, generator=_gen(1110 + k)), 2 + 2 * (k % 2)))
             for k in range(n)]
    return sym, asym


INPUTS = {"pointcloud": cloud_inputs, "points": points_inputs, "image": image_inputs}


# ------------------------------------------------------------------ inputs without symmetry (issue 50)


def block_shuffle(img: torch.Tensor, block: int, g: torch.Generator) -> torch.Tensor:
    """``img (C, H, W)`` with its ``block``-px tiles permuted at random (H, W multiples of block)."""
    c, h, w = img.shape
    tiles = img.reshape(c, h // block, block, w // block, block).permute(1, 3, 0, 2, 4).reshape(-1, c, block, block)
    tiles = tiles[torch.randperm(tiles.shape[0], generator=g)]
    return tiles.reshape(h // block, w // block, c, block, block).permute(2, 0, 3, 1, 4).reshape(c, h, w)


def _photo(path: Path, h: int, w: int) -> torch.Tensor:
    import cv2

    bgr = cv2.resize(cv2.imread(str(path)), (w, h), interpolation=cv2.INTER_AREA)
    return torch.from_numpy(bgr[..., ::-1].copy()).permute(2, 0, 1).float() / 255


def _texture_crop(name: str, h: int, w: int, g: torch.Generator) -> torch.Tensor:
    import skimage.data

    tex = torch.from_numpy(getattr(skimage.data, name)()).float() / 255  # (512, 512)
    y, x = (int(torch.randint(0, tex.shape[0] - h + 1, (1,), generator=g)), int(torch.randint(0, tex.shape[1] - w + 1, (1,), generator=g)))
    return tex[y : y + h, x : x + w].expand(3, -1, -1).clone()


def _framed(img: torch.Tensor, colour: float, pad: int, sigma: float) -> torch.Tensor:
    """``img (C, h, w)`` inside a constant ``pad``-px frame of ``colour``, then smoothed by ``sigma`` (0: not)."""
    out = torch.nn.functional.pad(img, (pad, pad, pad, pad), value=colour)
    return _smooth(out, sigma) if sigma > 0 else out


def image_families(n: int) -> dict[str, list]:
    h, w = 240, 320
    fam: dict[str, list] = {
        "uniform noise": [torch.rand(3, h, w, generator=_gen(2000 + k)) for k in range(n)],
        "box-smoothed noise (avg_pool 9)": [
            torch.nn.functional.avg_pool2d(torch.rand(1, 3, h, w, generator=_gen(2100 + k)), 9, 1, 4)[0] for k in range(n)
        ],
    }
    for sigma in (2, 4, 8):
        fam[f"Gaussian-smoothed noise sigma {sigma}"] = [_smooth(torch.rand(3, h, w, generator=_gen(2200 + 10 * sigma + k)), sigma) for k in range(n)]
    for colour, word in ((0.0, "zero"), (1.0, "white")):  # issue 56: a constant frame around noise
        fam[f"noise in a 20-px {word} frame, smoothed by sigma 0 / 2 / 4 in turn"] = [
            _framed(torch.rand(3, h - 40, w - 40, generator=_gen(2500 + 10 * int(colour) + k)), colour, 20, (0, 2, 4)[k % 3])
            for k in range(n)
        ]
    photos = sorted(PHOTOS.glob("*.jpg"))
    if photos:
        fam["dev photos shuffled by 40-px blocks"] = [block_shuffle(_photo(photos[k % len(photos)], h, w), 40, _gen(2300 + k)) for k in range(n)]
    fam["skimage grass / gravel crops"] = [_texture_crop(("grass", "gravel")[k % 2], h, w, _gen(2400 + k)) for k in range(n)]
    return fam


def ellipsoid_union(n: int, g: torch.Generator) -> torch.Tensor:
    """``(n, 3)`` points on three random ellipsoid surfaces at random places and orientations."""
    parts = []
    for i in range(3):
        m = n // 3 + (i < n % 3)
        d = torch.randn(m, 3, generator=g, dtype=torch.float64)
        d = d / d.norm(dim=1, keepdim=True)
        axes = 0.3 + torch.rand(3, generator=g, dtype=torch.float64)
        q, _ = torch.linalg.qr(torch.randn(3, 3, generator=g, dtype=torch.float64))
        parts.append((d * axes) @ q.T + torch.randn(3, generator=g, dtype=torch.float64))
    return torch.cat(parts).float()


def bent(points: torch.Tensor, g: torch.Generator) -> torch.Tensor:
    """``points (N, 3)`` normalised, then bent and twisted by random smooth amounts (breaks a symmetry)."""
    p = points.double()
    p = (p - p.mean(0)) / p.std(0).max()
    a = 0.3 + 0.4 * torch.rand(3, generator=g, dtype=torch.float64)
    x, y, z = p.unbind(1)
    x2 = x + a[0] * y**2 + 0.2 * torch.sin(2 * z + a[1])
    ang = a[2] * z
    y2, z2 = y * torch.cos(ang) - x2 * torch.sin(ang) * 0.3, z + 0.25 * x2 * y
    return torch.stack([x2, y2, z2], 1).float()


def cloud_families(n: int) -> dict[str, list]:
    fam: dict[str, list] = {
        "5-Gaussian mixture": [gaussian_mixture(4000, 3, 2500 + k) for k in range(n)],
        "three random ellipsoids": [ellipsoid_union(4000, _gen(2600 + k)) for k in range(n)],
    }
    meshes = [m for m in (_read_mesh(name) for name in ("bunny00.off", "cow.off", "armadillo.off")) if m is not None]
    if meshes:
        fam["bent mesh surfaces (bunny, cow, armadillo)"] = [
            bent(sample_surface(meshes[k % len(meshes)], 4000, generator=_gen(2700 + k)), _gen(2750 + k)) for k in range(n)
        ]
    return fam


def points_families(n: int) -> dict[str, list]:
    dims = (3, 6, 10, 20)
    return {
        "Gaussian n=100": [torch.randn(100, dims[k % 4], generator=_gen(2800 + k), dtype=torch.float64) for k in range(n)],
        "5-Gaussian mixture n=300": [gaussian_mixture(300, dims[k % 4], 2900 + k).double() for k in range(n)],
    }


NO_SYMMETRY = {"image": image_families, "pointcloud": cloud_families, "points": points_families}
#: inputs per family for the slow detectors (tens of seconds per 240 x 320 image on this machine)
SLOW_N = {"pointsymm_image": 4}


def run_no_symmetry(name: str, kind: str, families: dict[str, list]) -> dict:
    config = {"input": kind, "steps": [{"name": name}]}
    row: dict = {"solver": name, "kind": kind, "families": {}}
    t0 = time.perf_counter()
    for fam, inputs in families.items():
        scores, refused = [], 0
        for data in inputs:
            try:
                scores.append(scalar_score(torchsym.detect(data, config, kind=kind)))
            except torchsym.errors.TorchsymError:
                refused += 1
        high = sum(s >= THRESHOLD for s in scores)
        row["families"][fam] = {"n": len(scores), "refused": refused, "at_or_above": high, "max": max(scores, default=0.0),
                                "median": statistics.median(scores) if scores else 0.0, "scores": scores}
        log.info("%s %s: %d of %d >= %.1f (max %.3f)", name, fam, high, len(scores), THRESHOLD, row["families"][fam]["max"])
    n = sum(f["n"] for f in row["families"].values())
    row["n"], row["at_or_above"] = n, sum(f["at_or_above"] for f in row["families"].values())
    row["share"] = row["at_or_above"] / max(n, 1)
    row["seconds"] = time.perf_counter() - t0
    return row


def no_symmetry_markdown(rows: list[dict], skipped: dict[str, str], n: int, load: str) -> str:
    lines = [
        "# Scores on inputs without symmetry (issue 50)",
        "",
        f"`python benchmarks/bench_scores.py --no-symmetry` ({n} inputs per family, "
        + ", ".join(f"{k}: {v}" for k, v in SLOW_N.items()) + "); every detector through "
        f"`torchsym.detect` with its default settings; a score >= {THRESHOLD} claims a symmetry. Target: < 5 % "
        f"of these inputs at or above {THRESHOLD}, for every detector. Load while it ran: {load}.",
        "",
        "| detector | kind | inputs | at or above 0.3 | share | worst family (share, max score) | time (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        worst = max(r["families"].items(), key=lambda kv: (kv[1]["at_or_above"] / max(kv[1]["n"], 1), kv[1]["max"]))
        wf = worst[1]
        lines.append(f"| {r['solver']} | {r['kind']} | {r['n']} | {r['at_or_above']} | {100 * r['share']:.1f} % | "
                     f"{worst[0]} ({100 * wf['at_or_above'] / max(wf['n'], 1):.0f} %, {wf['max']:.3f}) | {r['seconds']:.0f} |")
    for name, why in skipped.items():
        lines.append(f"| {name} | {SOLVERS.get(name).kind} | {why} | | | | |")
    lines += ["", "Box-smoothed noise is `avg_pool2d(noise, 9, 1, 4)` (issue 50's case): its zero padding leaves a "
              "dark 4-px frame on all four sides, a symmetric structure; the same noise with `count_include_pad=False`, "
              "reflect padding or the border cropped scores 0 with boundary cliques (`docs/design/bad_input.md`)."]
    lines += ["", "## By family", "", "| detector | family | inputs | at or above 0.3 | median | max | refused |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        for fam, f in r["families"].items():
            lines.append(f"| {r['solver']} | {fam} | {f['n']} | {f['at_or_above']} | {f['median']:.3f} | {f['max']:.3f} | {f['refused']} |")
    return "\n".join(lines) + "\n"


def main_no_symmetry(args: argparse.Namespace) -> None:
    import os

    n = 3 if args.quick else args.n
    families = {kind: make(n) for kind, make in NO_SYMMETRY.items()}
    rows, skipped = [], {}
    load0 = os.getloadavg()
    for name in SOLVERS.names():
        entry = SOLVERS.get(name)
        if args.only and name not in args.only:
            continue
        if name in SKIPPED or entry.kind not in families:
            skipped[name] = SKIPPED.get(name, f"no inputs of kind {entry.kind!r} in this benchmark")
            continue
        fams = {f: inputs[: SLOW_N.get(name, len(inputs))] for f, inputs in families[entry.kind].items()}
        rows.append(run_no_symmetry(name, entry.kind, fams))
    load = f"uptime load {load0[0]:.1f} at the start, {os.getloadavg()[0]:.1f} at the end (2 cores shared)"
    md = no_symmetry_markdown(rows, skipped, n, load)
    print(md)
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    (out / "scores_no_symmetry.md").write_text(md)
    (out / "scores_no_symmetry.json").write_text(json.dumps({"threshold": THRESHOLD, "n_per_family": n, "rows": rows,
                                                              "skipped": skipped, "load": load}, indent=1))


def scalar_score(result) -> float:
    """The result's ``score``, or the best axis's score (0 without axes)."""
    if hasattr(result, "score"):
        return float(result.score)
    scores = result.scores
    return float(scores[0]) if len(scores) else 0.0


def roc_auc(sym: list[float], asym: list[float]) -> float:
    """P(a symmetric input scores above an asymmetric one), ties counting half."""
    wins = sum((s > a) + 0.5 * (s == a) for s in sym for a in asym)
    return wins / (len(sym) * len(asym))


def run_solver(name: str, kind: str, inputs) -> dict:
    config = {"input": kind, "steps": [{"name": name}]}
    out = {"solver": name, "kind": kind, "symmetric": [], "asymmetric": []}
    t0 = time.perf_counter()
    for label, cases in (("symmetric", inputs[0]), ("asymmetric", inputs[1])):
        for what, data in cases:
            t = time.perf_counter()
            try:
                score = scalar_score(torchsym.detect(data, config, kind=kind))
                out[label].append({"input": what, "score": score, "seconds": time.perf_counter() - t})
            except torchsym.errors.TorchsymError as exc:  # a refusal is reported, not fatal
                out[label].append({"input": what, "score": None, "error": str(exc)})
            log.info("%s %s %s: %s", name, label, what, out[label][-1].get("score"))
    s = [c["score"] for c in out["symmetric"] if c["score"] is not None]
    a = [c["score"] for c in out["asymmetric"] if c["score"] is not None]
    if s and a:
        out.update(median_symmetric=statistics.median(s), median_asymmetric=statistics.median(a),
                   max_asymmetric=max(a), min_symmetric=min(s), auc=roc_auc(s, a))
    out["seconds"] = time.perf_counter() - t0
    return out


def to_markdown(rows: list[dict], skipped: dict[str, str]) -> str:
    lines = [
        "# Score calibration: symmetric against asymmetric inputs (issue 31)",
        "",
        "`python benchmarks/bench_scores.py`; every solver through `torchsym.detect` with its default settings; "
        "shared 2-core machine, times noisy. Target of issue 31: asymmetric inputs below 0.3, symmetric ones high.",
        "",
        "| solver | kind | median score symmetric | median score asymmetric | max asymmetric | min symmetric | ROC AUC | time (s) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if "auc" in r:
            lines.append(
                f"| {r['solver']} | {r['kind']} | {r['median_symmetric']:.3f} | {r['median_asymmetric']:.3f} | "
                f"{r['max_asymmetric']:.3f} | {r['min_symmetric']:.3f} | {r['auc']:.2f} | {r['seconds']:.0f} |"
            )
        else:
            lines.append(f"| {r['solver']} | {r['kind']} | - | - | - | - | - | {r['seconds']:.0f} |")
    for name, why in skipped.items():
        lines.append(f"| {name} | {SOLVERS.get(name).kind} | {why} | | | | | |")
    lines += ["", "## Every input", "", "| solver | input | symmetric | score | time (s) |", "|---|---|---|---|---|"]
    for r in rows:
        for label in ("symmetric", "asymmetric"):
            for c in r[label]:
                score = f"{c['score']:.3f}" if c["score"] is not None else f"refused: {c['error']}"
                lines.append(f"| {r['solver']} | {c['input']} | {label == 'symmetric'} | {score} | {c.get('seconds', 0):.1f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer inputs per solver")
    parser.add_argument("--only", nargs="*", help="run only these solvers")
    parser.add_argument("--threads", type=int, default=1, help="torch threads (default: %(default)s)")
    parser.add_argument("--out", type=Path, default=HERE / "results", help="folder of the results files")
    parser.add_argument("--no-symmetry", action="store_true", help="the share of inputs without symmetry scoring >= 0.3")
    parser.add_argument("--n", type=int, default=10, help="inputs per family with --no-symmetry")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    torch.set_num_threads(args.threads)
    if args.no_symmetry:
        main_no_symmetry(args)
        return
    inputs = {kind: make(args.quick) for kind, make in INPUTS.items()}
    rows, skipped = [], {}
    for name in SOLVERS.names():
        entry = SOLVERS.get(name)
        if args.only and name not in args.only:
            continue
        if name in SKIPPED or entry.kind not in inputs:
            skipped[name] = SKIPPED.get(name, f"no inputs of kind {entry.kind!r} in this benchmark")
            continue
        rows.append(run_solver(name, entry.kind, inputs[entry.kind]))
        log.info("%s done in %.0f s", name, rows[-1]["seconds"])
    write_report(args.out, "scores", to_markdown(rows, skipped), {"rows": rows, "skipped": skipped})


if __name__ == "__main__":
    main()
