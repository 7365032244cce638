"""Time per photograph of the image pipelines as users run them (issues 32 and 36).

For every photo of ``--data`` (the 32 dev photographs by default) and every config, in
one process and interleaved photo by photo (so a change of load hits every config alike):
the wall and process-CPU seconds of ``torchsym.detect(path, config)`` (reading the file
included), after one warm-up call per config. A config given as ``NAME@WxH`` gets the photo
resized to ``W x H`` first (as a tensor), for targets stated at a size (SymmSLIC: 640 x 480).

Usage: python benchmarks/bench_photo_time.py [--data DIR] [--threads 1]
       [--configs configs/image_axes.yaml configs/image_symmslic.yaml@640x480 configs/image_symmetry_map.yaml@640x480]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import torch
from report import write_report

import torchsym
from torchsym.io import read_image

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_CONFIGS = ["configs/image_axes.yaml", "configs/image_symmslic.yaml@640x480", "configs/image_symmetry_map.yaml@640x480"]


def _input(path: Path, size: tuple[int, int] | None):
    if size is None:
        return str(path)
    img = read_image(path)  # (C, H, W) float in [0, 1]
    return torch.nn.functional.interpolate(img[None], size=(size[1], size[0]), mode="bilinear", align_corners=False)[0]


def _parse(entry: str) -> tuple[str, tuple[int, int] | None]:
    name, _, size = entry.partition("@")
    if not size:
        return name, None
    w, h = size.lower().split("x")
    return name, (int(w), int(h))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(ROOT.parent / "shared" / "data" / "images" / "reflection_single_dev"))
    ap.add_argument("--configs", nargs="+", default=DEFAULT_CONFIGS)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    args = ap.parse_args(argv)
    import cv2
    from threadpoolctl import threadpool_limits

    torch.set_num_threads(args.threads)
    cv2.setNumThreads(args.threads)
    threadpool_limits(args.threads)  # BLAS and OpenMP, as on a runner's worker
    photos = sorted(p for p in Path(args.data).iterdir() if p.suffix.lower() in (".jpg", ".jpeg", ".png"))
    if not photos:
        print(f"no photos in {args.data}")
        return 0
    configs = [_parse(c) for c in args.configs]
    times: dict[str, list[tuple[str, float, float]]] = {c: [] for c in args.configs}
    for entry, (cfg, size) in zip(args.configs, configs):  # warm-up: imports, caches
        torchsym.detect(_input(photos[0], size), str(ROOT / cfg))
    for photo in photos:
        for entry, (cfg, size) in zip(args.configs, configs):
            data = _input(photo, size)
            w0, c0 = time.perf_counter(), time.process_time()
            torchsym.detect(data, str(ROOT / cfg))
            times[entry].append((photo.name, time.perf_counter() - w0, time.process_time() - c0))
        print(photo.name, {e: round(times[e][-1][1], 3) for e in args.configs}, flush=True)
    load = os.getloadavg()[0]
    lines = [
        "# Time per photograph through `torchsym.detect` (issues 32 and 36)",
        "",
        f"`python benchmarks/bench_photo_time.py --threads {args.threads}`; {len(photos)} photos of `{Path(args.data).name}`, "
        f"torch, OpenCV and BLAS threads {args.threads}, configs interleaved photo by photo, one warm-up call each; {os.cpu_count()} cores, torch {torch.__version__}, "
        f"load average {load:.1f} at the end. `NAME@WxH`: the photo resized to W x H first; otherwise the file as it comes.",
        "",
        "| config | photos | median wall s | max wall s | median CPU s | max CPU s | over 1 s (wall) | slowest |",
        "|---|---|---|---|---|---|---|---|",
    ]
    rows = []
    for entry in args.configs:
        t = times[entry]
        walls, cpus = [x[1] for x in t], [x[2] for x in t]
        slowest = max(t, key=lambda x: x[1])[0]
        rows.append({"config": entry, "n": len(t), "median_wall": statistics.median(walls), "max_wall": max(walls),
                     "median_cpu": statistics.median(cpus), "max_cpu": max(cpus), "over_1s": sum(w > 1.0 for w in walls),
                     "slowest": slowest, "per_photo": t})
        r = rows[-1]
        lines.append(f"| {entry} | {r['n']} | {r['median_wall']:.3f} | {r['max_wall']:.3f} | {r['median_cpu']:.3f} | "
                     f"{r['max_cpu']:.3f} | {r['over_1s']} | {slowest} |")
    write_report(args.out, "photo_time", "\n".join(lines) + "\n", {"threads": args.threads, "load": load, "rows": rows})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
