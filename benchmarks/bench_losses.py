"""Forward + backward time of the symmetry distance loss against a dense ``cdist`` formulation.

Front door: none; it times a loss (``torchsym.losses``), not a detection pipeline.

The case of the issue: 32 clouds x 1,000 points x 3 planes (float32), loss
``mean_i min_j |S p_i - p_j|^2`` per cloud and plane, summed, then ``backward()`` to the
planes and the points. Rows:

* ``symmetry_distance, tree``: :func:`torchsym.losses.symmetry_distance`, nearest
  neighbours from scipy's kd-tree without gradient, the residual differentiated;
* ``symmetry_distance, brute``: the same with chunked ``cdist`` + ``argmin`` without gradient
  (the path on accelerators and under ``torch.compile``);
* ``dense cdist``: reflect, ``torch.cdist`` to the cloud ``(B, K, N, N)``, ``min``, mean,
  all under autograd (the formulation many training codes use).

The three run interleaved (A, B, C, A, B, C, ...) in one process after one warm-up each;
each cell is the median over ``--repeats``, in wall time and in this process's CPU time
(the latter is less sensitive to other jobs on a shared machine). The max relative difference of the losses
and the plane gradients against the dense row is reported too (they agree: same
nearest neighbours, same residuals). On a CUDA device (``--device cuda``) the tree row
is skipped. Times on a shared machine are noisy.

Usage: python benchmarks/bench_losses.py [--threads 1] [--repeats 5] [--out benchmarks/results]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

import torch

from torchsym.losses import reflect_batch, symmetry_distance
from report import write_report  # benchmarks/report.py


def dense_loss(points: torch.Tensor, normal: torch.Tensor, offset: torch.Tensor) -> torch.Tensor:
    refl = reflect_batch(points, normal, offset)  # (B, K, N, D)
    d = torch.cdist(refl, points.unsqueeze(1).expand(-1, refl.shape[1], -1, -1))  # (B, K, N, N)
    return (d.min(-1).values ** 2).mean(-1)  # (B, K)


def make_case(b: int, n: int, k: int, device: torch.device, seed: int = 0):
    g = torch.Generator().manual_seed(seed)
    half = torch.randn(b, n // 2, 3, generator=g)
    pts = torch.cat([half, half * torch.tensor([-1.0, 1.0, 1.0])], 1).to(device)
    normal = torch.randn(b, k, 3, generator=g).to(device)
    offset = (0.1 * torch.randn(b, k, generator=g)).to(device)
    return pts, normal, offset


def run_once(fn, pts, normal, offset, device):
    p = pts.clone().requires_grad_()
    n = normal.clone().requires_grad_()
    o = offset.clone().requires_grad_()
    if device.type == "cuda":
        torch.cuda.synchronize(device)
    t0, c0 = time.perf_counter(), time.process_time()
    loss = fn(p, n, o)
    loss.sum().backward()
    if device.type == "cuda":
        torch.cuda.synchronize(device)
    return (time.perf_counter() - t0, time.process_time() - c0), loss.detach(), n.grad.detach()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--clouds", type=int, default=32)
    ap.add_argument("--points", type=int, default=1000)
    ap.add_argument("--planes", type=int, default=3)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--out", default="benchmarks/results")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    device = torch.device(args.device)
    pts, normal, offset = make_case(args.clouds, args.points, args.planes, device)
    rows = {
        "symmetry_distance, tree": lambda p, n, o: symmetry_distance(p, n, o, method="tree"),
        "symmetry_distance, brute": lambda p, n, o: symmetry_distance(p, n, o, method="brute"),
        "dense cdist": dense_loss,
    }
    if device.type != "cpu":
        rows.pop("symmetry_distance, tree")
    times: dict[str, list[float]] = {name: [] for name in rows}
    cpu: dict[str, list[float]] = {name: [] for name in rows}
    results = {}
    for name, fn in rows.items():  # warm-up
        results[name] = run_once(fn, pts, normal, offset, device)[1:]
    for _ in range(args.repeats):  # interleaved
        for name, fn in rows.items():
            wall, proc = run_once(fn, pts, normal, offset, device)[0]
            times[name].append(wall)
            cpu[name].append(proc)
    ref_loss, ref_grad = results["dense cdist"]
    dense_median = statistics.median(times["dense cdist"])
    table = []
    for name in rows:
        loss, grad = results[name]
        med = statistics.median(times[name])
        table.append(
            {
                "method": name,
                "median_s": med,
                "min_s": min(times[name]),
                "cpu_median_s": statistics.median(cpu[name]),
                "speedup_vs_dense": dense_median / med,
                "loss_rel_diff": float(((loss - ref_loss).abs().max() / ref_loss.abs().max())),
                "grad_rel_diff": float(((grad - ref_grad).abs().max() / ref_grad.abs().max())),
            }
        )
    title = (
        f"# Symmetry distance, forward + backward: {args.clouds} clouds x {args.points} points x {args.planes} planes, "
        f"{device.type}, {args.threads} thread(s)"
    )
    lines = [
        title,
        "",
        f"Command: `python {' '.join(sys.argv)}`; median of {args.repeats} interleaved runs after a warm-up; "
        f"torch {torch.__version__}. Wall times on a shared machine are noisy; the process CPU time "
        "(all threads of this process) shows the work itself.",
        "",
        "| method | median s | min s | process CPU s (median) | dense / this | loss rel. diff | plane-grad rel. diff |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in table:
        lines.append(
            f"| {r['method']} | {r['median_s']:.4f} | {r['min_s']:.4f} | {r['cpu_median_s']:.4f} | {r['speedup_vs_dense']:.1f}x | "
            f"{r['loss_rel_diff']:.1e} | {r['grad_rel_diff']:.1e} |"
        )
    text = "\n".join(lines) + "\n"
    write_report(args.out, "losses", text, {"command": " ".join(sys.argv), "torch": torch.__version__, "rows": table})


if __name__ == "__main__":
    main()
