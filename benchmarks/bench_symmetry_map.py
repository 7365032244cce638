"""Benchmark of the dense reflection symmetry map (thesis Ch. 3) and its three schemes.

Front door: not ``torchsym.detect``; the map is scored alone, with ``n_axes`` set to the planted
axes (the config leaves the count to the axes detector).

In one process, on the same inputs:

- a seeded synthetic set (``--synthetic``, default 20) of 640 x 480 photos made by
  :func:`torchsym.image.synthetic.mirrored_photo` from the 32 dev photographs (``--photos``;
  textures when absent): one object whose left half is mirrored onto its right about a
  random axis, pasted on a mosaic of other crops, with illumination change, a 1 px warp,
  noise and JPEG, so the mirror field is exact at every object pixel. Per scheme (IRS,
  MMP, BMP; the same candidate pairs and cluster for all three): the correspondence rate
  against tau over the symmetric region (Sec. 3.3.2, Fig. 3.7), SSIM and PSNR of
  ``Im = S I(f)`` over that region (and for IRS against the iteration, Fig. 3.8), SSM
  precision / recall / F_beta / AUC against the region (Sec. 3.3.3), and the seconds per
  stage of the full solver (IRS, one axis; and three axes on the first 5 images);
- the Leeds Butterflies images (``--butterflies``, default /work/data/butterflies, fetched
  from github dsw88/cs601r-project1-dataset, dataset/butterflies/; skipped when absent):
  SSM scores against the segmentation masks, one axis per image.

Rule for the butterflies, written before any result was seen: the file names of
``dataset/butterflies/images`` sorted, every 20th from the first (1st, 21st, ...), at most
40; all of them, whatever the view (``benchmarks/results/symmetry_map_butterflies.txt``
lists them). No setting is tuned per image; the solver's defaults with ``n_axes`` given.

    python benchmarks/bench_symmetry_map.py [--synthetic 20] [--butterflies DIR] [--limit N]

Timings are wall time on a shared machine (noisy); set ``--threads``.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np
import torch

from torchsym.image.symmetry_map import SymmetryMapSettings, symmetry_map
from torchsym.image.symmetry_map.estimate import cluster_field
from torchsym.image.synthetic import mirrored_photo
from torchsym.io import read_image
from torchsym.metrics.symmetry_map import nmrf_correspondence_rate, reconstruction_quality, ssm_scores
from report import write_report  # benchmarks/report.py

HERE = Path(__file__).resolve().parent
TAUS = (1, 2, 3, 4, 5, 6, 8, 10, 15, 20)
SCHEMES = ("irs", "mmp", "bmp")


def _mean(xs):
    xs = [x for x in xs if x is not None and np.isfinite(x)]
    return float(np.mean(xs)) if xs else float("nan")


def run_synthetic(n: int, photos: str, n_three: int) -> dict:
    rates = {s: [] for s in SCHEMES}
    quality = {s: [] for s in SCHEMES}
    ssm = {s: [] for s in SCHEMES}
    per_iter: list[list[tuple[float, float]]] = []
    stages: list[dict[str, float]] = []
    totals, totals3, cpu, cpu3 = [], [], [], []
    misses = 0
    for i in range(n):
        d = mirrored_photo(height=480, width=640, photo_dir=photos, generator=torch.Generator().manual_seed(1000 + i))
        img, truth, mask = d["image"], d["nmrf"], d["mask"]
        t, c = time.perf_counter(), time.process_time()
        res = symmetry_map(img, n_axes=1)
        totals.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
        stages.append(res.seconds)
        if len(res) == 0:
            misses += 1
            for s in SCHEMES:
                rates[s].append([0.0] * len(TAUS))
            continue
        pairs = res.pairs[res.pair_cluster == 0]
        settings = SymmetryMapSettings(n_axes=1)
        fields = {"irs": (res.nmrf[0], res.ssm[0])}
        for s in ("mmp", "bmp"):
            nmrf, sc, _ = cluster_field(res.image[None], pairs, settings.replace({"patchmatch.scheme": s}), torch.Generator().manual_seed(0))
            fields[s] = (nmrf, sc)
        for s, (nmrf, sc) in fields.items():
            rates[s].append(nmrf_correspondence_rate(nmrf, truth, mask, TAUS).tolist())
            quality[s].append(reconstruction_quality(img, nmrf, sc, mask))
            ssm[s].append(ssm_scores(sc, mask))
        history: list[torch.Tensor] = []
        _, sc, _ = cluster_field(res.image[None], pairs, settings, torch.Generator().manual_seed(0), history=history)
        per_iter.append([reconstruction_quality(img, f, None, mask) for f in history])
        if i < n_three:
            t, c = time.perf_counter(), time.process_time()
            symmetry_map(img, n_axes=3)
            totals3.append(time.perf_counter() - t)
            cpu3.append(time.process_time() - c)
    out = {
        "n_images": n,
        "no_axis": misses,
        "taus": list(TAUS),
        "rate": {s: np.mean(np.array(rates[s]), 0).tolist() for s in SCHEMES},
        "rate_at_5_per_image": {s: [r[TAUS.index(5)] for r in rates[s]] for s in SCHEMES},
        "ssim": {s: _mean([q[0] for q in quality[s]]) for s in SCHEMES},
        "psnr": {s: _mean([q[1] for q in quality[s]]) for s in SCHEMES},
        "ssim_per_iter": np.mean([[q[0] for q in it] for it in per_iter], 0).tolist() if per_iter else [],
        "psnr_per_iter": np.mean([[q[1] for q in it] for it in per_iter], 0).tolist() if per_iter else [],
        "ssm": {s: _ssm_summary(ssm[s]) for s in SCHEMES},
        "seconds_total_median": statistics.median(totals),
        "seconds_total_max": max(totals),
        "seconds_three_axes_median": statistics.median(totals3) if totals3 else None,
        "cpu_seconds_median": statistics.median(cpu),
        "cpu_seconds_three_axes_median": statistics.median(cpu3) if cpu3 else None,
        "load_average": list(__import__("os").getloadavg()),
        "seconds_stage_median": {k: statistics.median([st.get(k, 0.0) for st in stages]) for k in stages[0]},
    }
    return out


def _ssm_summary(scores) -> dict:
    return {
        "precision": _mean([s.precision for s in scores]),
        "recall": _mean([s.recall for s in scores]),
        "f_beta_0_09": _mean([s.f_beta_0_09 for s in scores]),
        "f_beta_0_3": _mean([s.f_beta_0_3 for s in scores]),
        "auc": _mean([s.auc for s in scores]),
        "pr_precision": np.mean([s.pr_precision.numpy() for s in scores], 0).tolist() if scores else [],
        "pr_recall": np.mean([s.pr_recall.numpy() for s in scores], 0).tolist() if scores else [],
        "n": len(scores),
    }


def run_butterflies(folder: Path, limit: int | None) -> dict | None:
    if not (folder / "images").is_dir():
        return None
    import cv2

    names = sorted(p.name for p in (folder / "images").glob("*.png"))[:limit]
    scores, secs, names_used = [], [], []
    for name in names:
        seg = folder / "segmentations" / name.replace(".png", "_seg0.png")
        if not seg.is_file():
            continue
        img = read_image(folder / "images" / name)
        t = time.perf_counter()
        res = symmetry_map(img, n_axes=1)
        secs.append(time.perf_counter() - t)
        m = cv2.imread(str(seg), cv2.IMREAD_GRAYSCALE)
        m = cv2.resize(m, (res.image.shape[-1], res.image.shape[-2]), interpolation=cv2.INTER_NEAREST) > 127
        scores.append(ssm_scores(res.score_map, torch.from_numpy(m)))
        names_used.append(name)
    (HERE / "results" / "symmetry_map_butterflies.txt").write_text("\n".join(names_used) + "\n")
    return {**_ssm_summary(scores), "seconds_median": statistics.median(secs) if secs else None}


def markdown(syn: dict, bfly: dict | None) -> str:
    lines = ["# Dense reflection symmetry map (thesis Ch. 3)", "", "`python benchmarks/bench_symmetry_map.py` "
             f"(synthetic: {syn['n_images']} seeded 640 x 480 images, {syn['no_axis']} without an axis).", ""]
    lines += ["## Correspondence rate against tau (px), symmetric region", "",
              "| scheme | " + " | ".join(f"tau {t}" for t in syn["taus"]) + " |",
              "|---|" + "---|" * len(syn["taus"])]
    for s in SCHEMES:
        lines.append(f"| {s.upper()} | " + " | ".join(f"{v:.3f}" for v in syn["rate"][s]) + " |")
    lines += ["", "## Reconstruction Im = S I(f) over the symmetric region, and SSM against it", "",
              "| scheme | SSIM | PSNR (dB) | SSM P | SSM R | F (beta^2 0.09) | F (beta^2 0.3) | AUC |", "|---|---|---|---|---|---|---|---|"]
    for s in SCHEMES:
        q = syn["ssm"][s]
        lines.append(f"| {s.upper()} | {syn['ssim'][s]:.3f} | {syn['psnr'][s]:.2f} | {q['precision']:.3f} | {q['recall']:.3f} | "
                     f"{q['f_beta_0_09']:.3f} | {q['f_beta_0_3']:.3f} | {q['auc']:.3f} |")
    lines += ["", "## IRS against the iteration (Im without the score weight, symmetric region)", "",
              "| iteration | " + " | ".join(str(i + 1) for i in range(len(syn["ssim_per_iter"]))) + " |",
              "|---|" + "---|" * len(syn["ssim_per_iter"]),
              "| SSIM | " + " | ".join(f"{v:.3f}" for v in syn["ssim_per_iter"]) + " |",
              "| PSNR | " + " | ".join(f"{v:.2f}" for v in syn["psnr_per_iter"]) + " |"]
    three = syn["seconds_three_axes_median"]
    cpu3 = syn["cpu_seconds_three_axes_median"]
    lines += ["", "## Seconds per 640 x 480 image (median; one torch thread on a shared 2-core CPU, noisy)", "",
              f"one axis: wall {syn['seconds_total_median']:.2f} s (max {syn['seconds_total_max']:.2f} s), CPU {syn['cpu_seconds_median']:.2f} s; "
              f"three axes: wall {three if three is None else round(three, 2)} s, CPU {cpu3 if cpu3 is None else round(cpu3, 2)} s; "
              f"load average at the end {', '.join(f'{v:.1f}' for v in syn['load_average'])} (wall time counts the other processes' share)", "",
              "| stage | " + " | ".join(syn["seconds_stage_median"]) + " |", "|---|" + "---|" * len(syn["seconds_stage_median"]),
              "| s | " + " | ".join(f"{v:.3f}" for v in syn["seconds_stage_median"].values()) + " |"]
    if bfly is not None:
        lines += ["", f"## Leeds Butterflies, SSM against the masks ({bfly['n']} images, one axis)", "",
                  "| P | R | F (beta^2 0.09) | F (beta^2 0.3) | AUC | s / image |", "|---|---|---|---|---|---|",
                  f"| {bfly['precision']:.3f} | {bfly['recall']:.3f} | {bfly['f_beta_0_09']:.3f} | {bfly['f_beta_0_3']:.3f} | {bfly['auc']:.3f} | {bfly['seconds_median']:.2f} |"]
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--synthetic", type=int, default=20)
    ap.add_argument("--photos", default=str(HERE.parents[1] / "shared" / "data" / "images" / "reflection_single_dev"))
    ap.add_argument("--butterflies", default="/work/data/butterflies")
    ap.add_argument("--limit", type=int, default=40)
    ap.add_argument("--three-axes", type=int, default=5, help="images also timed with three axes")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    syn = run_synthetic(args.synthetic, args.photos, args.three_axes)
    bfly = run_butterflies(Path(args.butterflies), args.limit)
    text = markdown(syn, bfly)
    write_report(args.out, "symmetry_map", text, {"synthetic": syn, "butterflies": bfly})


if __name__ == "__main__":
    main()
