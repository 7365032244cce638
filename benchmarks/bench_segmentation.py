"""Symmetric-object segmentation against ground-truth masks (thesis Secs. 4.3.1 and 3.3.3).

Front door: not ``torchsym.detect``; ``symm_slic`` and ``symmetry_map`` run with the settings of
``configs/image_symmslic.yaml`` and ``configs/image_symmetry_map.yaml`` (the map with ``n_axes: 1``, one object per mask).

Data (fetched, never committed): the GrabCut and Berkeley interactive-segmentation sets
of ``SamsungLabs/ritm_interactive_segmentation`` at commit ``c05f992`` (``--ritm``, the
folder holding ``GrabCut/{data_GT, boundary_GT}`` and ``Berkeley/masks``); the Berkeley
images are the BSDS500 images of the same id (``--bsds``, the folder holding
``data/images/{train,val,test}``).

Rule for the symmetric subsets, written down and the list made
(``benchmarks/data/symmetric_masks.txt``, ``--make-list``) before any method was run on
these images; it reads the ground-truth masks only:

* the object: GrabCut mask values 255 and the grey unlabelled band (128) along its
  outline; Berkeley mask channel 0 above 127;
* the mask is shrunk (area interpolation, then > 0.5) so its longer side is 240 px;
* one object: the largest 8-connected component holds at least 90 % of the object's pixels;
* bilateral symmetry: the best IoU of the mask with its reflection
  (:func:`torchsym.metrics.best_reflection_iou`: axes through the centroid every 1
  degree, each shifted across itself by -0.1, -0.05, 0, 0.05, 0.1 times the equivalent
  radius ``sqrt(area / pi)``) is at least 0.85.

Measured in one run, per image (settings from the configs, never tuned on these images):

* (a) SymmSLIC's unsupervised mask (Sec. 4.3.1: the union of the mirror superpixel pairs;
  ``configs/image_symmslic.yaml``) and OpenCV's ``cv2.grabCut`` given the mask's bounding
  box widened by 5 % of its width and height on each side (5 iterations;
  definite and probable foreground; where the box covers the whole image grabCut has no
  background to learn from and the box itself is its answer): segmentation error
  (:func:`torchsym.metrics.segmentation_error`) over all pixels (the thesis's
  normalisation) and over the box's pixels (GrabCut in One Cut's), GrabCut's grey band
  ignored; for SymmSLIC also its mask's precision and recall, and, as a probe of where
  the error comes from, the angle between its strongest detected axis and the mask's best
  reflection axis and the distance of the mask's centroid from that axis;
* (b) the dense symmetry map's SSM (``configs/image_symmetry_map.yaml`` with one axis,
  ``n_axes = 1``): precision, recall, F_beta (beta^2 = 0.09 and 0.3) at 100/255 and ROC AUC
  (:func:`torchsym.metrics.ssm_scores`) against the mask, the grey band left out;
* seconds per image of each method (wall clock, one torch and OpenCV thread, on a shared
  2-core machine under other jobs' load: indicative only).

Rows: the symmetric subsets, and the whole sets. To keep the run near 10 minutes the
whole-set rows use every image of the symmetric subset and every ``--every``-th (default
5th) of the others, sorted by name, each stratum weighted by its size in the whole set
(a stratified estimate, ``--every 1`` for the exact figure); grabCut, which is cheap,
runs on every image.

    PYTHONPATH=. python benchmarks/bench_segmentation.py [--every 5] [--ritm DIR] [--bsds DIR]
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
import torch
import yaml
from scipy import ndimage

from torchsym.image.symmetry_map import symmetry_map
from torchsym.image.symmslic import symm_slic
from torchsym.io import read_image
from torchsym.metrics.masks import best_reflection_iou
from torchsym.metrics.superpixels import segmentation_error
from torchsym.metrics.symmetry_map import ssm_scores
from torchsym.runner.truth import read_object_mask
from report import write_report

ROOT = Path(__file__).resolve().parents[1]
LIST = ROOT / "benchmarks" / "data" / "symmetric_masks.txt"
RULE_SIDE, RULE_COMPONENT, RULE_IOU = 240, 0.90, 0.85


def mask_paths(ritm: Path) -> list[tuple[str, str, Path]]:
    """``(set, id, mask path)`` of every mask, sorted."""
    out = [("GrabCut", p.stem, p) for p in sorted((ritm / "GrabCut" / "boundary_GT").glob("*.bmp"))]
    out += [("Berkeley", p.stem, p) for p in sorted((ritm / "Berkeley" / "masks").glob("*.png"))]
    return out


read_mask = read_object_mask  # (object, ignore): GrabCut's 128 band unlabelled; Berkeley's 0 / 255


def small_mask(obj: np.ndarray) -> np.ndarray:
    """``obj`` resized so that its longer side is ``RULE_SIDE`` px (area average, > 0.5)."""
    s = RULE_SIDE / max(obj.shape)
    return cv2.resize(obj.astype(np.float32), None, fx=s, fy=s, interpolation=cv2.INTER_AREA) > 0.5


def mask_axis(obj: np.ndarray) -> tuple[np.ndarray, float]:
    """The mask's best reflection axis ``n . (x, y) + c = 0`` (``n`` unit, ``(2,)``) in the
    mask's own pixels, found on its ``RULE_SIDE``-px copy (:func:`small_mask`)."""
    s = RULE_SIDE / max(obj.shape)
    _, n, off = best_reflection_iou(small_mask(obj))
    off = off + float(n.sum()) * (0.5 * s - 0.5)  # small pixel x_s = (x + 0.5) s - 0.5
    return np.asarray(n, dtype=np.float64), float(off / s)


def symmetric_items(ritm: Path, bsds: Path) -> list[tuple[str, str, Path, Path]]:
    """``(set, name, image, mask)`` of the images on the committed symmetric list."""
    sym = {line.strip() for line in LIST.read_text().splitlines() if line.strip() and not line.startswith("#")}
    out = []
    for st, name, mpath in mask_paths(ritm):
        path = image_path(st, name, ritm, bsds)
        if f"{st}/{name}" in sym and path is not None:
            out.append((st, name, path, mpath))
    return out


def rule(path: Path) -> dict:
    """The selection rule's figures for one mask (see the module docstring)."""
    obj, band = read_mask(path)
    small = small_mask(obj | band)
    comp, n = ndimage.label(small, structure=np.ones((3, 3)))
    share = 0.0 if n == 0 else float(np.bincount(comp.reshape(-1))[1:].max() / small.sum())
    iou, _, _ = best_reflection_iou(small)
    return {"component_share": share, "reflection_iou": iou, "symmetric": share >= RULE_COMPONENT and iou >= RULE_IOU}


def make_list(ritm: Path) -> list[str]:
    names, lines = [], []
    for st, name, path in mask_paths(ritm):
        r = rule(path)
        lines.append(f"{st}/{name} component {r['component_share']:.3f} iou {r['reflection_iou']:.3f} {'*' if r['symmetric'] else ''}")
        print(lines[-1], flush=True)
        if r["symmetric"]:
            names.append(f"{st}/{name}")
    LIST.parent.mkdir(parents=True, exist_ok=True)
    LIST.write_text(
        "# set/id of the masks with one bilaterally symmetric object (rule: benchmarks/bench_segmentation.py docstring)\n"
        + "\n".join(names) + "\n"
    )
    return names


def config_params(name: str) -> dict:
    """The first step's params of ``configs/<name>.yaml``."""
    return yaml.safe_load((ROOT / "configs" / f"{name}.yaml").read_text())["steps"][0]["params"]


def image_path(st: str, name: str, ritm: Path, bsds: Path) -> Path | None:
    if st == "GrabCut":
        found = [p for p in (ritm / "GrabCut" / "data_GT").iterdir() if p.stem == name]
    else:  # a second object of one image carries a letter: 239007a is image 239007
        found = [bsds / "data" / "images" / d / f"{name.rstrip('abcdefghij')}.jpg" for d in ("train", "val", "test")]
        found = [p for p in found if p.is_file()]
    return found[0] if found else None


def grabcut_box(obj: np.ndarray) -> tuple[int, int, int, int]:
    """``(x0, y0, x1, y1)``: the object's bounding box widened by 5 % of its size on each side."""
    ys, xs = np.nonzero(obj)
    h, w = obj.shape
    bw, bh = xs.max() - xs.min() + 1, ys.max() - ys.min() + 1
    mx, my = int(round(0.05 * bw)), int(round(0.05 * bh))
    return max(0, xs.min() - mx), max(0, ys.min() - my), min(w, xs.max() + 1 + mx), min(h, ys.max() + 1 + my)


def axis_probe(obj: np.ndarray, normals: torch.Tensor, offsets: torch.Tensor) -> dict:
    """Angle (deg) between the strongest detected axis and the mask's best reflection axis,
    and the distance (px) of the mask's centroid from the detected axis."""
    _, n_mask, _ = best_reflection_iou(small_mask(obj))
    if len(normals) == 0:
        return {"axis_found": False, "axis_angle_deg": None, "centroid_distance_px": None}
    n = normals[0].double().numpy()
    cos = abs(float(n @ n_mask)) / float(np.linalg.norm(n) * np.linalg.norm(n_mask))
    ys, xs = np.nonzero(obj)
    dist = abs(float(n[0] * xs.mean() + n[1] * ys.mean() + float(offsets[0]))) / float(np.linalg.norm(n))
    return {"axis_found": True, "axis_angle_deg": math.degrees(math.acos(min(1.0, cos))), "centroid_distance_px": dist}


def precision_recall(pred: np.ndarray, obj: np.ndarray, ignore: np.ndarray) -> tuple[float, float]:
    keep = ~ignore
    tp = float((pred & obj & keep).sum())
    return (tp / max(1.0, float((pred & keep).sum()))), (tp / max(1.0, float((obj & keep).sum())))


def timed(fn, *args, **kwargs):
    t = time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - t


def measure_grabcut(path: Path, obj: np.ndarray, band: np.ndarray) -> dict:
    """grabCut's figures of one image (see the module docstring)."""
    box = grabcut_box(obj)
    row: dict = {}
    bgr = cv2.imread(str(path))
    gc = np.zeros(obj.shape, np.uint8)
    bgd, fgd = np.zeros((1, 65)), np.zeros((1, 65))
    rect = (box[0], box[1], box[2] - box[0], box[3] - box[1])
    t = time.perf_counter()
    try:
        cv2.grabCut(bgr, gc, rect, bgd, fgd, 5, cv2.GC_INIT_WITH_RECT)
        row["grabcut_no_background"] = False
    except cv2.error:  # the box covers the whole image: no background samples, the box is the answer
        gc[box[1] : box[3], box[0] : box[2]] = cv2.GC_PR_FGD
        row["grabcut_no_background"] = True
    row["grabcut_seconds"] = time.perf_counter() - t
    e = segmentation_error((gc == cv2.GC_FGD) | (gc == cv2.GC_PR_FGD), obj, box=box, ignore=band)
    row["grabcut_error_image"], row["grabcut_error_box"] = e["over_image"], e["over_box"]
    return row


def measure(path: Path, mask_path: Path, slic_params: dict, map_params: dict) -> dict:
    """Every figure of one image (see the module docstring)."""
    obj, band = read_mask(mask_path)
    img = read_image(path)
    if tuple(img.shape[-2:]) != obj.shape:
        raise RuntimeError(f"{path}: image {tuple(img.shape[-2:])} and mask {obj.shape} differ")
    box = grabcut_box(obj)
    row: dict = {}
    res, row["symmslic_seconds"] = timed(symm_slic, img, slic_params)
    pred = res.mask.numpy()
    e = segmentation_error(pred, obj, box=box, ignore=band)
    row["symmslic_error_image"], row["symmslic_error_box"] = e["over_image"], e["over_box"]
    row["symmslic_precision"], row["symmslic_recall"] = precision_recall(pred, obj, band)
    row.update(axis_probe(obj, res.normals, res.offsets))
    row.update(measure_grabcut(path, obj, band))
    smap, row["ssm_seconds"] = timed(symmetry_map, img, map_params)
    score = smap.score_map
    if tuple(score.shape) != obj.shape:
        raise RuntimeError(f"{path}: SSM {tuple(score.shape)} and mask {obj.shape} differ")
    keep = torch.from_numpy(~band)
    sc = ssm_scores(score[keep][None], torch.from_numpy(obj)[keep][None])
    row.update(ssm_precision=sc.precision, ssm_recall=sc.recall, ssm_f_beta_0_09=sc.f_beta_0_09,
               ssm_f_beta_0_3=sc.f_beta_0_3, ssm_auc=sc.auc)
    return row


FIGURES = ("symmslic_error_image", "symmslic_error_box", "grabcut_error_image", "grabcut_error_box",
           "ssm_auc", "ssm_precision", "ssm_recall", "ssm_f_beta_0_09", "ssm_f_beta_0_3")
SECONDS = ("symmslic_seconds", "grabcut_seconds", "ssm_seconds")


def summary(rows: list[dict], weights: dict[bool, float]) -> dict:
    """Means of :data:`FIGURES` (strata ``symmetric`` True / False weighted by ``weights``),
    medians of :data:`SECONDS`."""
    out: dict = {"n_measured": sum(r["sampled"] for r in rows)}
    for key in FIGURES:
        total, wsum = 0.0, 0.0
        for sym, wt in weights.items():
            vals = [r[key] for r in rows if r["symmetric"] == sym and r.get(key) is not None and np.isfinite(r[key])]
            if vals and wt > 0:
                total, wsum = total + wt * statistics.fmean(vals), wsum + wt
        out[key] = total / wsum if wsum else float("nan")
    for key in SECONDS:
        vals = [r[key] for r in rows if key in r]
        out[key] = statistics.median(vals) if vals else float("nan")
    return out


def markdown(table: list[tuple[str, dict]], probe: dict, args) -> str:
    lines = ["# Symmetric-object segmentation against ground-truth masks (thesis 4.3.1, 3.3.3)", "",
             f"`PYTHONPATH=. python benchmarks/bench_segmentation.py --every {args.every}`; GrabCut and Berkeley masks of "
             "SamsungLabs/ritm_interactive_segmentation (c05f992), Berkeley images from BSDS500. Symmetric subsets by the "
             "rule in the benchmark's docstring (`benchmarks/data/symmetric_masks.txt`). One torch / OpenCV thread on a "
             "2-core machine shared with other jobs (load average about 15): seconds are wall clock and indicative only.", "",
             "Segmentation error = misclassified pixels over all pixels (thesis) / over the box's pixels (GrabCut in One Cut); "
             "GrabCut's grey band ignored. grabCut is given the mask's bounding box + 5 % margin; SymmSLIC gets nothing.", "",
             "| rows | images (measured; grabCut on all) | SymmSLIC err / all px | SymmSLIC err / box px | grabCut err / all px | grabCut err / box px "
             "| SSM AUC | SSM P | SSM R | F (beta^2 0.09) | F (beta^2 0.3) | s SymmSLIC | s grabCut | s SSM |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, sm in table:
        lines.append(f"| {name} | {sm['n_images']} ({sm['n_measured']}) | " + " | ".join(f"{sm[k]:.3f}" for k in FIGURES)
                     + " | " + " | ".join(f"{sm[k]:.2f}" for k in SECONDS) + " |")
    lines += ["", "## Targets (issues 35, 36)", "",
              "| target | value | measured (symmetric subsets, both sets) |", "|---|---|---|"]
    both = dict(table)["symmetric, both sets"]
    gc50 = dict(table)["whole GrabCut"]
    lines += [f"| SymmSLIC segmentation error, all pixels (thesis's own figure) | <= 0.19 | {both['symmslic_error_image']:.3f} |",
              f"| grabCut with a box, 50 GrabCut images, all pixels (issue's anchor) | ~0.048 | {gc50['grabcut_error_image']:.3f} (whole GrabCut row) |",
              f"| SSM AUC | >= 0.85 | {both['ssm_auc']:.3f} |",
              f"| SSM F_beta, beta = 0.3 (beta^2 = 0.09) | >= 0.68 | {both['ssm_f_beta_0_09']:.3f} |"]
    lines += ["", f"grabCut's box covered the whole image (no background; the box is its answer) on {probe['gc_no_bg']} images."]
    lines += ["", "## Probe: SymmSLIC's mask on the symmetric subsets", "",
              f"mask precision {probe['precision']:.3f}, recall {probe['recall']:.3f} (means); an axis found on "
              f"{probe['found']} of {probe['n']} images; strongest detected axis within 10 degrees of the mask's best "
              f"reflection axis and within 10 % of the image diagonal of the mask's centroid on {probe['agree']} of "
              f"{probe['n']}; median angle {probe['angle_median']:.1f} degrees, median centroid distance "
              f"{probe['dist_median']:.1f} px; error over all pixels where the axis agrees {probe['err_agree']:.3f}, "
              f"elsewhere {probe['err_other']:.3f}; an empty mask would score {probe['empty']:.3f}."]
    return "\n".join(lines) + "\n"


def probe_summary(rows: list[dict], diag: dict[str, float]) -> dict:
    sym = [r for r in rows if r["symmetric"] and r["sampled"]]
    agree = [r for r in sym if r["axis_found"] and r["axis_angle_deg"] <= 10 and r["centroid_distance_px"] <= 0.1 * diag[r["name"]]]
    other = [r for r in sym if r not in agree]
    found = [r for r in sym if r["axis_found"]]
    mean = lambda rs, k: statistics.fmean(r[k] for r in rs) if rs else float("nan")  # noqa: E731
    return {"n": len(sym), "found": len(found), "agree": len(agree),
            "precision": mean(sym, "symmslic_precision"), "recall": mean(sym, "symmslic_recall"),
            "angle_median": statistics.median(r["axis_angle_deg"] for r in found) if found else float("nan"),
            "dist_median": statistics.median(r["centroid_distance_px"] for r in found) if found else float("nan"),
            "err_agree": mean(agree, "symmslic_error_image"), "err_other": mean(other, "symmslic_error_image"),
            "empty": mean(sym, "empty_error_image"), "gc_no_bg": sum(r["grabcut_no_background"] for r in rows)}


def run(args) -> int:
    torch.set_num_threads(1)
    cv2.setNumThreads(1)
    symmetric = {line.strip() for line in LIST.read_text().splitlines() if line.strip() and not line.startswith("#")}
    slic_params = config_params("image_symmslic")
    map_params = {**config_params("image_symmetry_map"), "n_axes": 1}
    every = {"GrabCut": 0, "Berkeley": 0}
    counts: dict[tuple[str, bool], int] = {}
    rows, diag = [], {}
    for st, name, mpath in mask_paths(args.ritm):
        key = f"{st}/{name}"
        sym = key in symmetric
        counts[(st, sym)] = counts.get((st, sym), 0) + 1
        path = image_path(st, name, args.ritm, args.bsds)
        if path is None:
            print(f"{key}: no image, skipped", flush=True)
            continue
        if not sym:
            every[st] += 1
            if (every[st] - 1) % args.every:  # outside the sample: grabCut only (it is cheap)
                rows.append({"set": st, "name": key, "symmetric": sym, "sampled": False, **measure_grabcut(path, *read_mask(mpath))})
                continue
        row = {"set": st, "name": key, "symmetric": sym, "sampled": True, **measure(path, mpath, slic_params, map_params)}
        obj, band = read_mask(mpath)
        row["empty_error_image"] = segmentation_error(np.zeros_like(obj), obj, ignore=band)["over_image"]
        diag[key] = math.hypot(*obj.shape)
        rows.append(row)
        print(key, {k: round(v, 3) for k, v in row.items() if isinstance(v, float)}, flush=True)
        if args.limit and sum(r["sampled"] for r in rows) >= args.limit:
            break
    table = []
    for label, sets, strata in (("symmetric", ("GrabCut", "Berkeley"), (True,)), ("whole", ("GrabCut", "Berkeley"), (True, False))):
        for sets_used in ((sets[0],), (sets[1],), sets):
            rs = [r for r in rows if r["set"] in sets_used and r["symmetric"] in strata]
            weights = {s: float(sum(counts.get((st, s), 0) for st in sets_used)) for s in strata}
            sm = summary(rs, weights)
            sm["n_images"] = int(sum(weights.values()))
            name = f"{label} {sets_used[0]}" if len(sets_used) == 1 else f"{label}, both sets"
            table.append((name, sm))
    probe = probe_summary(rows, diag)
    write_report(args.out, "segmentation", markdown(table, probe, args),
                 {"args": {k: str(v) for k, v in vars(args).items()}, "table": dict(table), "probe": probe, "rows": rows})
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ritm", type=Path, default=Path("/work/data/ritm/datasets"))
    ap.add_argument("--bsds", type=Path, default=Path("/work/data/bsds/BSDS500"))
    ap.add_argument("--make-list", action="store_true", help="apply the rule to the masks and write the list, then stop")
    ap.add_argument("--every", type=int, default=5, help="measure every n-th image outside the symmetric subsets")
    ap.add_argument("--limit", type=int, default=0, help="stop after this many images (a smoke run; 0: all)")
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = ap.parse_args(argv)
    if args.make_list:
        names = make_list(args.ritm)
        print(f"{len(names)} symmetric masks written to {LIST}")
        return 0
    return run(args)


if __name__ == "__main__":
    sys.exit(main())
