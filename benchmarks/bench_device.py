"""The solvers on a CUDA device beside the CPU, in one run on one machine.

Front door: not ``torchsym.detect``; the solvers' functions run on tensors placed on each device
(the front door reads files into CPU tensors).

Inputs are generated in code (seeded), so the script needs no data folder:

* reflection plane of a point cloud (:func:`torchsym.detect_reflection_plane`) on
  planted symmetric clouds of 3,000 to 300,000 points, clean and with 100 % outliers; on
  the CPU its nearest neighbours come from scipy's kd-tree, on the GPU from chunked
  ``torch.cdist`` with exact re-ranking, or the host's kd-tree past 3e8 distances
  (:class:`torchsym.matching.knn.KNNIndex`);
* k-symmetry axes of an image (:func:`torchsym.ksymmetry_axes`): kornia's SIFT runs on the
  image's device;
* PointSymm (:func:`torchsym.point_symm`): the assignment and the trust region run on the
  CPU whatever the input's device, so this row shows the cost of the round trip alone;
* nearest neighbours (:class:`torchsym.matching.knn.KNNIndex`) by brute force on the device
  against the host's kd-tree, to place ``brute_force_max``.

Each cell is the median of ``--repeats`` timed runs after one warm-up run; GPU times wait
for the device (``torch.cuda.synchronize``). The angle columns are each result's error
against the planted plane, so the table also shows that both paths find the same plane.

Usage: python benchmarks/bench_device.py [--threads 2] [--repeats 3] [--out benchmarks/results]
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

import torch

import torchsym
from torchsym.geometry import plane_angle
from torchsym.image.synthetic import mirrored_objects_image
from torchsym.matching.knn import KNNIndex
from report import write_report


def _sync(device: torch.device) -> None:
    if device.type == "cuda":
        torch.cuda.synchronize(device)


def _timed(fn, device: torch.device, repeats: int):
    fn()  # warm-up: kernels compiled, allocator primed
    times, out = [], None
    for _ in range(repeats):
        _sync(device)
        t0 = time.perf_counter()
        out = fn()
        _sync(device)
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def _brute_mm(points: torch.Tensor, queries: torch.Tensor, k: int, chunk: int = 4096) -> torch.Tensor:
    """Indices of the ``k`` nearest points by ``cdist``'s matrix-product form (for comparison)."""
    out = [torch.cdist(queries[s : s + chunk], points).topk(k, dim=1, largest=False)[1] for s in range(0, queries.shape[0], chunk)]
    return torch.cat(out)


def _deg(a: torch.Tensor, b: torch.Tensor) -> float:
    return float(plane_angle(a.detach().cpu().double(), b.detach().cpu().double())) * 180 / math.pi


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--threads", type=int, default=2, help="CPU threads for torch (the CPU column)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--sizes", type=int, nargs="+", default=[3000, 30000, 300000])
    ap.add_argument("--knn-sizes", type=int, nargs="+", default=[3000, 30000, 300000])
    ap.add_argument("--brute-limit", type=float, default=2e9, help="skip brute-force kNN rows above this many distances")
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    args = ap.parse_args(argv)
    if not torch.cuda.is_available():
        print("bench_device: no CUDA device on this machine; nothing to compare", file=sys.stderr)
        return 1
    torch.set_num_threads(args.threads)
    cpu, gpu = torch.device("cpu"), torch.device("cuda")
    rows = []

    def row(task: str, size: str, fn_cpu, fn_gpu, truth=None):
        t_cpu, r_cpu = _timed(fn_cpu, cpu, args.repeats)
        t_gpu, r_gpu = _timed(fn_gpu, gpu, args.repeats)
        rec = {"task": task, "size": size, "cpu_s": t_cpu, "gpu_s": t_gpu, "speedup": t_cpu / t_gpu}
        if truth is not None:
            rec["cpu_deg"], rec["gpu_deg"] = _deg(r_cpu.normal, truth), _deg(r_gpu.normal, truth)
        rows.append(rec)
        print(rec, flush=True)

    for n in args.sizes:
        cloud = torchsym.planted_symmetric_cloud(n, generator=1)
        for tau, label in ((0.0, "clean"), (1.0, "100 % outliers")):
            c = torchsym.add_outliers(cloud, tau, generator=2) if tau else cloud
            p_cpu, p_gpu = c.points, c.points.to(gpu)
            row(
                f"plane, {label}",
                f"{c.points.shape[0]:,} points",
                lambda p=p_cpu: torchsym.detect_reflection_plane(p, generator=0),
                lambda p=p_gpu: torchsym.detect_reflection_plane(p, generator=0),
                cloud.normal,
            )
    for h, w in ((360, 480), (1080, 1440)):
        img, _ = mirrored_objects_image(2, height=h, width=w, generator=torch.Generator().manual_seed(0))
        i_gpu = img.to(gpu)
        row("k-symmetry axes", f"{w}x{h} image", lambda i=img: torchsym.ksymmetry_axes(i), lambda i=i_gpu: torchsym.ksymmetry_axes(i))
    s = torchsym.make_symmetric_pointset(2000, 3, 0.0, generator=torch.Generator().manual_seed(0))
    row(
        "PointSymm",
        "2,000 points, 3-D",
        lambda: torchsym.point_symm(s.points, generator=torch.Generator().manual_seed(1)),
        lambda p=s.points.to(gpu): torchsym.point_symm(p, generator=torch.Generator().manual_seed(1)),
        s.normal,
    )

    # where brute force on the device and the host's kd-tree cross (KNNIndex.brute_force_max)
    knn_rows = []
    for n_pts in args.knn_sizes:
        pts = torch.rand(n_pts, 3, generator=torch.Generator().manual_seed(0)).to(gpu)
        for m in sorted({min(3000, n_pts), n_pts}):
            q = torch.rand(m, 3, generator=torch.Generator().manual_seed(1)).to(gpu)
            for k in (1, 10):
                if m * n_pts > args.brute_limit:
                    continue
                brute = KNNIndex(pts, brute_force_max=math.inf)
                t_brute, (_, i_b) = _timed(lambda b=brute, q=q, k=k: b.query(q, k=k), gpu, args.repeats)
                t_mm, i_mm = _timed(lambda p=pts, q=q, k=k: _brute_mm(p, q, k), gpu, args.repeats)
                t0 = time.perf_counter()
                tree = KNNIndex(pts, brute_force_max=0, workers=args.threads)
                tree.query(q[:1])
                t_build = time.perf_counter() - t0
                t_tree, (_, i_t) = _timed(lambda t=tree, q=q, k=k: t.query(q, k=k), gpu, args.repeats)
                same = float((i_b == i_t).double().mean())
                same_mm = float((i_mm.view_as(i_t) == i_t).double().mean())
                rec = {
                    "points": n_pts, "queries": m, "k": k, "brute_s": t_brute, "mm_s": t_mm, "tree_s": t_tree,
                    "build_s": t_build, "same": same, "same_mm": same_mm,
                }
                knn_rows.append(rec)
                print(rec, flush=True)

    name = torch.cuda.get_device_name(gpu)
    lines = [
        f"# Solvers on {name} beside the CPU ({args.threads} torch threads)",
        "",
        f"Command: `python benchmarks/bench_device.py --threads {args.threads} --repeats {args.repeats}`; "
        f"median of {args.repeats} runs after a warm-up; torch {torch.__version__}.",
        "",
        "| task | size | CPU s | GPU s | CPU / GPU | CPU error deg | GPU error deg |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        err = (f"{r['cpu_deg']:.3f} | {r['gpu_deg']:.3f}") if "cpu_deg" in r else "- | -"
        lines.append(f"| {r['task']} | {r['size']} | {r['cpu_s']:.3f} | {r['gpu_s']:.3f} | {r['speedup']:.2f}x | {err} |")
    lines += [
        "",
        "Nearest neighbours on the device (float32, uniform in the unit cube): KNNIndex's brute force",
        "(``cdist`` candidates in float64, k + 4 of them re-ranked by exact distances) against the host's kd-tree",
        "(query time with the copies both ways; the tree is built once per index, `build s`).",
        "``brute (mm)`` is ``cdist``'s matrix-product form |x|^2 + |y|^2 - 2 x.y alone: as fast, but in",
        "float32 it swaps close neighbours (its `same index` column against the tree).",
        "",
        "| points | queries | k | queries x points | brute s | brute (mm) s | tree s | tree build s | brute / tree |"
        " same index, brute | same index, mm |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in knn_rows:
        lines.append(
            f"| {r['points']:,} | {r['queries']:,} | {r['k']} | {r['points'] * r['queries']:.1e} | {r['brute_s']:.4f} | "
            f"{r['mm_s']:.4f} | {r['tree_s']:.4f} | {r['build_s']:.4f} | {r['brute_s'] / r['tree_s']:.2f} | "
            f"{r['same']:.4f} | {r['same_mm']:.4f} |"
        )
    meta = {"device": name, "threads": args.threads, "repeats": args.repeats, "torch": torch.__version__}
    write_report(args.out, "device", "\n".join(lines) + "\n", {"meta": meta, "rows": rows, "knn": knn_rows})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
