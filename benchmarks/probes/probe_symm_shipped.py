"""The shipped dense-map and SymmSLIC configs on photos with an exactly mirrored object,
each method taking its own axes from the axis stage (no ``n_axes``, no ``axes=``).

Images: :func:`torchsym.image.synthetic.mirrored_photo` (640 x 480; an object whose left
half is mirrored onto its right about a random axis, pasted on a mosaic of crops of the dev
photographs, with illumination change, a 1 px warp, noise and JPEG), seeds ``0 .. n-1``.
Per image: ``torchsym.detect(image, configs/image_symmetry_map.yaml)``: seconds, axes run,
the best field's correspondence rate at 5 px over the object's symmetric pixels;
``torchsym.detect(image, configs/image_symmslic.yaml)``: seconds, the mirror consistency
(:func:`torchsym.metrics.superpixels.mirror_consistency`) of its superpixels about the true
axis over those pixels. Writes ``benchmarks/results/symmetry_map_shipped.md`` and ``.json``.

    PYTHONPATH=.:benchmarks python benchmarks/probes/probe_symm_shipped.py [--n 8]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

import torch

import torchsym
from torchsym.image.synthetic import mirrored_photo
from torchsym.metrics.superpixels import mirror_consistency
from torchsym.metrics.symmetry_map import nmrf_correspondence_rate

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=8)
    ap.add_argument("--photos", default=str(ROOT.parent / "shared/data/images/reflection_single_dev"))
    args = ap.parse_args()
    torch.set_num_threads(1)
    photos = args.photos if Path(args.photos).is_dir() else None
    load0 = os.getloadavg()[0]
    rows = []
    for seed in range(args.n):
        ex = mirrored_photo(photo_dir=photos, generator=torch.Generator().manual_seed(seed))
        img, mask, line = ex["image"], ex["mask"], ex["line"].double()
        t0 = time.perf_counter()
        sm = torchsym.detect(img, ROOT / "configs/image_symmetry_map.yaml")
        t_map = time.perf_counter() - t0
        rate = max((float(nmrf_correspondence_rate(f, ex["nmrf"], mask, taus=(5,))[0]) for f in sm.nmrf), default=0.0)
        t0 = time.perf_counter()
        ss = torchsym.detect(img, ROOT / "configs/image_symmslic.yaml")
        t_slic = time.perf_counter() - t0
        n = line[:2] / line[:2].norm()
        mc = mirror_consistency(ss.labels, n, float(line[2] / line[:2].norm()), region=mask)
        rows.append({"seed": seed, "map_s": t_map, "map_axes": len(sm), "map_rate5": rate, "slic_s": t_slic,
                     "slic_consistency": mc, "slic_notes": list(getattr(ss, "notes", []))})
        print(rows[-1], flush=True)
    lines = ["# Shipped dense map and SymmSLIC, axes from the axis stage", "",
             f"`PYTHONPATH=.:benchmarks python benchmarks/probes/probe_symm_shipped.py --n {args.n}`; one thread, load average "
             f"{load0:.1f} at the start, {os.getloadavg()[0]:.1f} at the end, on 2 shared cores (times indicative).", "",
             "| seed | map s | map axes | field right at 5 px | SymmSLIC s | mirror consistency |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['seed']} | {r['map_s']:.2f} | {r['map_axes']} | {r['map_rate5']:.3f} | {r['slic_s']:.2f} | "
                     f"{r['slic_consistency']:.3f} |")
    med = {k: statistics.median(r[k] for r in rows) for k in ("map_s", "map_rate5", "slic_s", "slic_consistency")}
    lines += ["", f"Medians: map {med['map_s']:.2f} s, field right {med['map_rate5']:.3f}; SymmSLIC {med['slic_s']:.2f} s, "
              f"mirror consistency {med['slic_consistency']:.3f}; consistency >= 0.9 on "
              f"{sum(r['slic_consistency'] >= 0.9 for r in rows)} / {len(rows)}."]
    text = "\n".join(lines) + "\n"
    print(text)
    (ROOT / "benchmarks/results/symmetry_map_shipped.md").write_text(text)
    (ROOT / "benchmarks/results/symmetry_map_shipped.json").write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
