"""SymmSLIC against the superpixel methods people use (thesis Sec. 4.3).

Front door: not ``torchsym.detect``; SymmSLIC runs at the peers' superpixel counts and with given
axes, settings the shipped config fixes.

In one run, on the same images:

* BSDS500 test images (fetched, never committed; ``--bsds DIR`` is the folder holding
  ``data/images/test`` and ``data/groundTruth/test``): boundary recall, undersegmentation
  error and achievable segmentation accuracy (D. Stutz's definitions,
  :mod:`torchsym.metrics.superpixels`), mean over the human ground truths and the best
  of them, against the number of superpixels each method actually produced, and time;
* mirror consistency (the IoU of each superpixel's reflection with its best partner,
  area-weighted) on synthetic images mirrored about a known axis
  (:func:`torchsym.image.synthetic.mirrored_texture_image`), and on the 32 dev photos about
  their ground-truth axis, within the band the axis segment spans.

Methods: SymmSLIC (its own detected axes; and, on the synthetic images, told the axis),
OpenCV's SLIC, SLICO, MSLIC, SEEDS and LSC (``cv2.ximgproc``), each asked for about
``--k`` superpixels (SLIC's region size ``sqrt(H W / k)``).

Usage: python benchmarks/bench_superpixels.py --bsds DIR [--n 50] [--k 500] [--synthetic 10]
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import scipy.io
import torch

from torchsym.image.symmslic import symm_slic
from torchsym.image.synthetic import mirrored_texture_image
from torchsym.metrics.superpixels import (
    achievable_segmentation_accuracy,
    boundary_recall,
    mirror_consistency,
    undersegmentation_error,
)
from report import write_report

ROOT = Path(__file__).resolve().parents[1]


def opencv_method(name: str):
    def run(rgb: np.ndarray, k: int) -> np.ndarray:
        h, w = rgb.shape[:2]
        size = max(2, int(round(math.sqrt(h * w / k))))
        lab = cv2.cvtColor(rgb, cv2.COLOR_RGB2LAB)
        if name == "seeds":
            s = cv2.ximgproc.createSuperpixelSEEDS(w, h, 3, k, 4)
            s.iterate(lab, 10)
        elif name == "lsc":
            s = cv2.ximgproc.createSuperpixelLSC(lab, size)
            s.iterate(10)
            s.enforceLabelConnectivity(25)
        else:
            algo = {"slic": cv2.ximgproc.SLIC, "slico": cv2.ximgproc.SLICO, "mslic": cv2.ximgproc.MSLIC}[name]
            s = cv2.ximgproc.createSuperpixelSLIC(lab, algorithm=algo, region_size=size, ruler=10.0)
            s.iterate(10)
            s.enforceLabelConnectivity(25)
        return s.getLabels()

    return run


def symmslic_method(rgb: np.ndarray, k: int, axis: torch.Tensor | None = None) -> np.ndarray:
    img = torch.from_numpy(rgb).permute(2, 0, 1).float() / 255.0
    return symm_slic(img, n_superpixels=k, known_axes=None if axis is None else axis[None]).labels.numpy()


METHODS = {"symmslic": symmslic_method, **{m: opencv_method(m) for m in ("slic", "slico", "mslic", "seeds", "lsc")}}


def timed(fn, *args):
    t0 = time.perf_counter()
    out = fn(*args)
    return out, time.perf_counter() - t0


def bsds_rows(folder: Path, n: int, k: int) -> list[dict]:
    images = sorted((folder / "data" / "images" / "test").glob("*.jpg"))[:n]
    rows = []
    for path in images:
        rgb = cv2.cvtColor(cv2.imread(str(path)), cv2.COLOR_BGR2RGB)
        gts = scipy.io.loadmat(str(folder / "data" / "groundTruth" / "test" / f"{path.stem}.mat"))["groundTruth"][0]
        truths = [g["Segmentation"][0, 0] for g in gts]
        for name, fn in METHODS.items():
            labels, secs = timed(fn, rgb, k)
            br = [boundary_recall(labels, t) for t in truths]
            use = [undersegmentation_error(labels, t) for t in truths]
            asa = [achievable_segmentation_accuracy(labels, t) for t in truths]
            rows.append({"image": path.stem, "method": name, "count": int(len(np.unique(labels))), "seconds": secs,
                         "br_mean": float(np.mean(br)), "br_best": float(np.max(br)), "use_mean": float(np.mean(use)),
                         "use_best": float(np.min(use)), "asa_mean": float(np.mean(asa)), "asa_best": float(np.max(asa))})
        print(path.stem, {r["method"]: round(r["br_mean"], 3) for r in rows[-len(METHODS):]}, flush=True)
    return rows


def band(shape: tuple[int, int], seg: list[float]) -> np.ndarray:
    """Pixels within the ground-truth axis segment's extent along it and half its length
    across it."""
    h, w = shape
    x1, y1, x2, y2 = seg
    d = np.array([x2 - x1, y2 - y1])
    length = np.linalg.norm(d)
    d /= length
    ys, xs = np.mgrid[0:h, 0:w]
    along = (xs - x1) * d[0] + (ys - y1) * d[1]
    across = -(xs - x1) * d[1] + (ys - y1) * d[0]
    return (along >= 0) & (along <= length) & (np.abs(across) <= length / 2)


def mirror_rows(n_synthetic: int, k: int, dev: Path | None) -> list[dict]:
    rows = []
    for s in range(n_synthetic):
        img, axis = mirrored_texture_image(generator=torch.Generator().manual_seed(1000 + s))
        rgb = (img.permute(1, 2, 0).numpy() * 255).round().astype(np.uint8)
        runs = {**{m: (fn, (rgb, k)) for m, fn in METHODS.items()}, "symmslic (axis given)": (symmslic_method, (rgb, k, axis))}
        for name, (fn, args) in runs.items():
            labels, secs = timed(fn, *args)
            rows.append({"set": "synthetic", "image": s, "method": name, "seconds": secs,
                         "mirror": mirror_consistency(labels, axis[:2], float(axis[2]))})
    if dev is not None and (dev / "axes.txt").is_file():
        truth: dict[str, list[list[float]]] = {}
        for line in (dev / "axes.txt").read_text().splitlines():
            if line.strip() and not line.startswith("#"):
                name_img, *xy = line.split()
                truth.setdefault(name_img, []).append([float(v) for v in xy])
        for name_img, segs in sorted(truth.items()):
            bgr = cv2.imread(str(dev / name_img))
            scale = 640 / max(bgr.shape[:2])
            bgr = cv2.resize(bgr, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
            rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
            seg = [v * scale for v in segs[0]]
            d = np.array([seg[2] - seg[0], seg[3] - seg[1]])
            nrm = np.array([-d[1], d[0]]) / np.linalg.norm(d)
            off = -float(nrm @ seg[:2])
            region = band(rgb.shape[:2], seg)
            for name, fn in METHODS.items():
                labels, secs = timed(fn, rgb, k)
                rows.append({"set": "dev photos", "image": name_img, "method": name, "seconds": secs,
                             "mirror": mirror_consistency(labels, nrm, off, region=region)})
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bsds", type=Path, default=None, help="BSDS500 folder (holding data/images/test)")
    ap.add_argument("--dev", type=Path, default=ROOT.parent / "shared" / "data" / "images" / "reflection_single_dev")
    ap.add_argument("--n", type=int, default=50, help="BSDS500 test images (sorted by name)")
    ap.add_argument("--k", type=int, default=500)
    ap.add_argument("--synthetic", type=int, default=10)
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = ap.parse_args(argv)
    torch.set_num_threads(1)
    cv2.setNumThreads(1)
    bsds = bsds_rows(args.bsds, args.n, args.k) if args.bsds is not None and args.bsds.is_dir() else []
    mirror = mirror_rows(args.synthetic, args.k, args.dev if args.dev.is_dir() else None)
    lines = ["# SymmSLIC against OpenCV's superpixels (thesis 4.3)", "",
             f"`python benchmarks/bench_superpixels.py --bsds DIR --n {args.n} --k {args.k} --synthetic {args.synthetic}`, "
             "one thread, this 2-core machine (shared with other jobs while it ran: times are indicative).", ""]
    if bsds:
        lines += [f"## BSDS500 test, first {args.n} images, asked for {args.k} superpixels", "",
                  "| method | superpixels (median) | BR mean / best | USE mean / best | ASA mean / best | seconds (median) |",
                  "|---|---|---|---|---|---|"]
        for m in METHODS:
            rs = [r for r in bsds if r["method"] == m]
            med = lambda key: statistics.median(r[key] for r in rs)  # noqa: E731
            mean = lambda key: statistics.fmean(r[key] for r in rs)  # noqa: E731
            lines.append(f"| {m} | {med('count'):.0f} | {mean('br_mean'):.3f} / {mean('br_best'):.3f} | "
                         f"{mean('use_mean'):.3f} / {mean('use_best'):.3f} | {mean('asa_mean'):.3f} / {mean('asa_best'):.3f} | "
                         f"{med('seconds'):.2f} |")
    lines += ["", "## Mirror consistency (area-weighted IoU of reflected superpixels with their best partner)", "",
              "| set | method | mirror consistency (mean) | seconds (median) |", "|---|---|---|---|"]
    for st in ("synthetic", "dev photos"):
        for m in dict.fromkeys(r["method"] for r in mirror if r["set"] == st):
            rs = [r for r in mirror if r["set"] == st and r["method"] == m]
            lines.append(f"| {st} | {m} | {statistics.fmean(r['mirror'] for r in rs):.3f} | {statistics.median(r['seconds'] for r in rs):.2f} |")
    write_report(args.out, "superpixels", "\n".join(lines) + "\n",
                 {"args": {k: str(v) for k, v in vars(args).items()}, "bsds": bsds, "mirror": mirror})
    return 0


if __name__ == "__main__":
    sys.exit(main())
