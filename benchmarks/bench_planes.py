"""Every reflection plane of a shape: precision, recall, count right and time (issue 53).

Truth by geometry. A plane is *true* when reflecting the surface moves each sample no
farther from the surface than two independent samples of it lie from each other: the
mean distance from the mirror images of one sample (20,000 points by area) to a second,
independent sample, over the mean distance from the first sample to the second (the
*distance ratio*), is at most 2. Planes within 1.3 are *exact* and must be found; planes
at 1.3-2 are *near* and may be reported. Each shape's exact planes come from an
exhaustive search on its clean surface: 2,000 normals of a Fibonacci half sphere through
the surface's centroid, the local minima of the ratio (within 8 degrees) refined by a
pattern search, planes within 3 degrees merged; an axis about which rotations by three
generic angles are within 1.3 is an *axis of revolution* (it must be found, and stands
for the planes through it). Reported planes and axes are judged by their own ratio on the
same two samples.

The shapes (``--n-shapes`` per family, each in a random pose):

* primitives made in code with known groups: boxes (3 planes), square prisms (5), cubes
  (9), regular n-gon prisms (n + 1), cylinders (an axis and 1 plane), cones (an axis),
  tables (2 or 4), chairs (1), shelves built from boxes;
* the CGAL meshes of ``../shared/data/meshes`` as they are, and mirror-completed by a
  random plane through their vertices' median (:func:`torchsym.mesh.synthetic.mirror_complete`);

each sampled at 20,000 points as it comes in turn: clean, with Gaussian noise (0.3 % of
the diagonal), with three holes (2 % of the points each), or with the density falling to
40 % along a random direction (the truth is always the clean surface's).
Shapes with an even index are the *choose* part (settings were chosen on them), odd the
*report* part; both are printed. Variants cycle over pairs of shapes, so both parts get each.

Methods: ``planes``, ``torchsym.detect(points, "configs/pointcloud_planes.yaml")`` (the
shipped config, no overrides); ``one plane``, the one-plane detector
(``configs/pointcloud_plane.yaml``), which returns one plane.

    python benchmarks/bench_planes.py            # writes benchmarks/results/planes.{md,json}
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import time
from pathlib import Path

import torch

import torchsym
from torchsym.geometry.reflection import reflection_transform
from torchsym.geometry.sampling import sphere_normals
from torchsym.manifolds.special_orthogonal import SpecialOrthogonal
from torchsym.mesh.synthetic import mirror_complete as mirror_complete_mesh
from torchsym.pointcloud import (
    box_mesh,
    boxes_mesh,
    chair_mesh,
    cone_mesh,
    prism_mesh,
    sample_surface,
    table_mesh,
)
from torchsym.geometry.mesh import Mesh
from torchsym.pointcloud.reflection_planes.distance_test import DistanceTest, distance_test
from torchsym.pointcloud.reflection_planes.revolution import candidate_axes, rotation_transforms

from report import write_report

EXACT, NEAR = 1.3, 2.0
VARIANTS = ("clean", "noise", "holes", "uneven")
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


# ---------------------------------------------------------------- shapes


def shelf_mesh(width: float, height: float, depth: float, shelves: int) -> Mesh:
    """A shelf: two sides, a top, a bottom, ``shelves`` evenly spaced boards, a back."""
    t = 0.03
    boxes = [((t, depth, height), (-width / 2, 0, 0)), ((t, depth, height), (width / 2, 0, 0))]
    for k in range(shelves + 2):
        z = -height / 2 + k * height / (shelves + 1)
        boxes.append(((width, depth, t), (0, 0, z)))
    boxes.append(((width, t, height), (0, depth / 2, 0)))
    return boxes_mesh(boxes)


def make_shapes(data: Path, n_per_family: int, seed: int) -> list[tuple[str, Mesh]]:
    """``(name, mesh)`` of every family, ``n_per_family`` each (the CGAL meshes: all)."""
    g = torch.Generator().manual_seed(seed)

    def u(lo, hi):
        return lo + (hi - lo) * float(torch.rand(1, generator=g))

    shapes = []
    for k in range(n_per_family):
        a, b = u(0.5, 1.0), u(0.2, 0.45)
        shapes.append((f"box{k}", box_mesh((1.0, a, b))))
        shapes.append((f"squareprism{k}", box_mesh((a, a, u(1.3, 2.0) * a))))
        shapes.append((f"cube{k}", box_mesh((a, a, a))))
        n = [3, 5, 6, 7, 8, 12][k % 6]
        shapes.append((f"prism{n}_{k}", prism_mesh(n, 1.0, u(0.3, 0.8))))
        shapes.append((f"cylinder{k}", prism_mesh(256, 1.0, u(0.6, 2.5))))
        shapes.append((f"cone{k}", cone_mesh(256, 1.0, u(0.8, 2.0))))
        square = k % 2 == 1
        w = u(0.9, 1.5)
        shapes.append((f"table{k}", table_mesh(w, w if square else u(0.5, 0.8) * w, u(0.6, 0.9))))
        shapes.append((f"chair{k}", chair_mesh(u(0.4, 0.6), u(0.4, 0.6), u(0.4, 0.5), u(0.4, 0.7))))
        shapes.append((f"shelf{k}", shelf_mesh(u(0.6, 1.2), u(0.8, 1.8), u(0.25, 0.45), 1 + k % 4)))
    for k, path in enumerate(sorted(data.glob("*.off"))):
        mesh = torchsym.io.read_mesh(path, dtype=torch.float64)
        shapes.append((path.stem, mesh))
        normal = torch.randn(3, generator=g, dtype=torch.float64)
        normal = normal / normal.norm()
        sym, _ = mirror_complete_mesh(mesh, normal.numpy(), float((mesh.vertices.double() @ normal).median()))
        shapes.append((f"{path.stem}_mirrored", Mesh(sym.vertices.double(), sym.faces)))
    return shapes


def posed(mesh: Mesh, g: torch.Generator) -> Mesh:
    """``mesh`` scaled to a unit diagonal and moved by a random rotation and translation."""
    v = mesh.vertices.double()
    v = (v - v.mean(0)) / float((v.max(0).values - v.min(0).values).norm())
    rot = SpecialOrthogonal(3).random_point(generator=g).double()
    return Mesh(v @ rot.T + torch.randn(3, generator=g, dtype=torch.float64), mesh.faces)


def variant_points(mesh: Mesh, variant: str, n: int, g: torch.Generator) -> torch.Tensor:
    """``n`` surface samples of ``mesh`` as :data:`VARIANTS` ``variant`` describes."""
    diag = float((mesh.vertices.max(0).values - mesh.vertices.min(0).values).norm())
    if variant == "clean":
        return sample_surface(mesh, n, generator=g)
    if variant == "noise":
        return sample_surface(mesh, n, generator=g) + 0.003 * diag * torch.randn(n, 3, generator=g, dtype=torch.float64)
    p = sample_surface(mesh, 3 * n, generator=g)
    if variant == "holes":
        keep = torch.ones(p.shape[0], dtype=torch.bool)
        for _ in range(3):
            r = (p - p[int(torch.randint(0, p.shape[0], (1,), generator=g))]).norm(dim=1)
            keep &= r > r.kthvalue(int(0.02 * p.shape[0])).values
        p = p[keep]
    else:  # uneven: density falls linearly to 40 % along a random direction
        d = torch.randn(3, generator=g, dtype=torch.float64)
        s = p @ (d / d.norm())
        s = (s - s.min()) / (s.max() - s.min())
        p = p[torch.rand(p.shape[0], generator=g, dtype=torch.float64) < 1 - 0.6 * s]
    return p[torch.randperm(p.shape[0], generator=g)[:n]]


# ---------------------------------------------------------------- truth


def pattern_search(test: DistanceTest, normal: torch.Tensor, centroid: torch.Tensor) -> tuple[torch.Tensor, float]:
    """The normal of locally least ratio near ``normal`` (planes through ``centroid``):
    eight tilts at 2, 1, 0.5, 0.25, 0.12 degrees, each step kept while it lowers the ratio."""
    best = float(test.plane_ratios(normal[None], -(normal @ centroid)[None])[0])
    ring = torch.linspace(0, 2 * math.pi, 9, dtype=torch.float64)[:-1]
    for step in (2.0, 1.0, 0.5, 0.25, 0.12):
        for _ in range(6):
            frame = torchsym.geometry.tangent_basis(normal)
            t = math.tan(math.radians(step))
            cand = normal + t * (torch.cos(ring)[:, None] * frame[:, 0] + torch.sin(ring)[:, None] * frame[:, 1])
            cand = cand / cand.norm(dim=1, keepdim=True)
            r = test.plane_ratios(cand, -(cand @ centroid))
            k = int(r.argmin())
            if float(r[k]) >= best:
                break
            normal, best = cand[k], float(r[k])
    return normal, best


def truth(mesh: Mesh, g: torch.Generator) -> dict:
    """The clean surface's exact and near planes and its axes of revolution (see the module)."""
    a = sample_surface(mesh, 20000, generator=g)
    b = sample_surface(mesh, 20000, generator=g)
    full = distance_test(a, b, 20000, g)
    coarse = distance_test(a, b, 400, g)
    fine = distance_test(a, b, 1500, g)
    centroid = torch.cat([a, b]).mean(0)
    normals = sphere_normals(2000)
    r = coarse.plane_ratios(normals, -(normals @ centroid))
    near = (normals @ normals.T).abs() > math.cos(math.radians(8.0))
    rmat = torch.where(near, r[None, :].expand(len(r), -1), torch.full_like(near, float("inf"), dtype=r.dtype))
    minima = ((r <= rmat.min(1).values) & (r < 1.25 * NEAR)).nonzero()[:, 0]
    planes: list[tuple[torch.Tensor, float]] = []
    for i in minima[r[minima].argsort()].tolist():
        n, _ = pattern_search(fine, normals[i], centroid)
        ratio = float(full.plane_ratios(n[None], -(n @ centroid)[None])[0])
        if ratio <= NEAR and all(float((n @ m).abs()) < math.cos(math.radians(3.0)) for m, _ in planes):
            planes.append((n, ratio))
    pn = torch.stack([p[0] for p in planes]) if planes else torch.zeros(0, 3, dtype=torch.float64)
    pb = -(pn @ centroid)
    centered = a - a.mean(0)
    exact_idx = [k for k, p in enumerate(planes) if p[1] <= EXACT]
    axes = []
    for d, p in candidate_axes(pn[exact_idx], pb[exact_idx], centered, centroid, 0.1):
        if any(float((d @ e).abs()) > math.cos(math.radians(5.0)) for e, _ in axes):
            continue
        angles = torch.tensor([2 * math.pi * ((1 + k) * GOLDEN % 1.0) for k in range(3)], dtype=torch.float64)
        if float(full.ratios(rotation_transforms(d, p, angles)).max()) <= EXACT:
            axes.append((d, p))
    on_axis = [any(abs(float(n @ d)) < math.sin(math.radians(3.0)) for d, _ in axes) for n, _ in planes]
    exact = [p for p, o in zip(planes, on_axis) if p[1] <= EXACT and not o]
    return {"a": a, "b": b, "centroid": centroid, "exact": exact, "axes": axes,
            "near": [p for p, o in zip(planes, on_axis) if EXACT < p[1] <= NEAR and not o]}


def cached_truth(mesh: Mesh, g: torch.Generator, cache: Path | None, key: str) -> dict:
    """:func:`truth`, read from ``cache/key.pt`` when there (the generator then advances
    as :func:`truth` would have advanced it: its state is stored beside)."""
    path = cache / f"{key}.pt" if cache is not None else None
    if path is not None and path.exists():
        t = torch.load(path)
        g.set_state(t.pop("generator"))
    else:
        t = truth(mesh, g)
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            torch.save({**t, "generator": g.get_state()}, path)
    t["test"] = distance_test(t["a"], t["b"], 20000, torch.Generator().manual_seed(0))
    return t


# ---------------------------------------------------------------- evaluation


def judge(result, t: dict) -> dict:
    """Precision, recall and count right of one result against the truth ``t``."""
    test = t["test"]
    if hasattr(result, "normals"):
        normals, offsets = result.normals.double(), result.offsets.double()
        axes = list(zip(result.continuous_axes.double(), result.axis_points.double()))
    else:  # the one-plane result: its plane when it scores above 0
        keep = result.score > 0
        normals = result.normal.double()[None][:keep]
        offsets = result.offset.double()[None][:keep]
        axes = []
    ratios = test.plane_ratios(normals, offsets).tolist() if normals.shape[0] else []
    angles = torch.tensor([2 * math.pi * ((1 + k) * GOLDEN % 1.0) for k in range(3)], dtype=torch.float64)
    axis_ratios = [float(test.ratios(rotation_transforms(d, p, angles)).max()) for d, p in axes]
    true = sum(r <= NEAR for r in ratios) + sum(r <= NEAR for r in axis_ratios)
    reported = len(ratios) + len(axis_ratios)
    found = 0
    for n, _ in t["exact"]:
        for m, b in zip(normals, offsets):
            if float((n @ m).abs()) > math.cos(math.radians(4.0)) and abs(float(m @ t["centroid"] + b)) < 0.02:
                found += 1
                break
    for d, _ in t["axes"]:
        if any(float((d @ e).abs()) > math.cos(math.radians(5.0)) for e, _ in axes):
            found += 1
    must = len(t["exact"]) + len(t["axes"])
    return {"reported": reported, "true": true, "must": must, "found": found,
            "count_right": found == must and true == reported, "ratios": [round(r, 3) for r in ratios + axis_ratios]}


def summarise(rows: list[dict], key: str) -> dict:
    """Pooled precision and recall, count-right rate and time of one method over ``rows``."""
    reported = sum(r[key]["reported"] for r in rows)
    true = sum(r[key]["true"] for r in rows)
    must = sum(r[key]["must"] for r in rows)
    found = sum(r[key]["found"] for r in rows)
    secs = sorted(r[key]["seconds"] for r in rows)
    cpus = sorted(r[key]["cpu_seconds"] for r in rows)
    return {
        "shapes": len(rows),
        "precision": true / reported if reported else 1.0,
        "recall": found / must if must else 1.0,
        "count_right": sum(r[key]["count_right"] for r in rows) / max(len(rows), 1),
        "median_s": statistics.median(secs) if secs else 0.0,
        "p90_s": secs[int(0.9 * (len(secs) - 1))] if secs else 0.0,
        "max_s": secs[-1] if secs else 0.0,
        "median_cpu_s": statistics.median(cpus) if cpus else 0.0,
        "p90_cpu_s": cpus[int(0.9 * (len(cpus) - 1))] if cpus else 0.0,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default=str(Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "meshes"))
    ap.add_argument("--n-shapes", type=int, default=4, help="shapes per family made in code")
    ap.add_argument("--n-points", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=53)
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results"))
    ap.add_argument("--stem", default="planes")
    ap.add_argument("--cache", default=None, help="folder caching each shape's truth (slow to compute)")
    ap.add_argument("--shard", default="0/1", help="i/n: run shapes with index = i mod n, write their rows only")
    ap.add_argument("--merge", nargs="*", default=None, help="row files of the shards to merge into the report")
    args = ap.parse_args(argv)
    torch.set_num_threads(1)
    root = Path(__file__).resolve().parents[1]
    planes_cfg = root / "configs" / "pointcloud_planes.yaml"
    one_cfg = root / "configs" / "pointcloud_plane.yaml"
    if args.merge is not None:
        rows = sorted((r for f in args.merge for r in json.loads(Path(f).read_text())), key=lambda r: r["index"])
        return report(rows, args)
    shapes = make_shapes(Path(args.data), args.n_shapes, args.seed)
    shard, n_shards = (int(v) for v in args.shard.split("/"))
    cache = Path(args.cache) if args.cache else None
    rows = []
    for idx, (name, mesh) in enumerate(shapes):
        if idx % n_shards != shard:
            continue
        g = torch.Generator().manual_seed(args.seed * 7919 + idx)
        mesh = posed(mesh, g)
        variant = VARIANTS[(idx // 2) % len(VARIANTS)]  # both parts get every variant
        t = cached_truth(mesh, g, cache, f"{args.seed}_{args.n_shapes}_{idx}")
        pts = variant_points(mesh, variant, args.n_points, g).float()
        row = {"index": idx, "shape": name, "variant": variant, "part": "choose" if idx % 2 == 0 else "report",
               "exact": len(t["exact"]), "axes": len(t["axes"]), "near": len(t["near"]),
               "exact_ratios": [round(p[1], 3) for p in t["exact"]]}
        for key, cfg in (("planes", planes_cfg), ("one_plane", one_cfg)):
            t0, c0 = time.perf_counter(), time.process_time()
            res = torchsym.detect(pts, cfg)
            sec, cpu = time.perf_counter() - t0, time.process_time() - c0
            row[key] = {**judge(res, t), "seconds": sec, "cpu_seconds": cpu}
        rows.append(row)
        p = row["planes"]
        print(f"{idx:3d} {name:24s} {variant:7s} exact {row['exact']} axes {row['axes']} near {row['near']} | "
              f"reported {p['reported']} true {p['true']} found {p['found']}/{p['must']} "
              f"{'OK ' if p['count_right'] else 'BAD'} {p['seconds']:.2f}s (CPU {p['cpu_seconds']:.2f}s) {p['ratios']}", flush=True)
        row["load"] = os.getloadavg()[0]
    if n_shards > 1:
        Path(args.out).mkdir(parents=True, exist_ok=True)
        (Path(args.out) / f"{args.stem}_rows{shard}.json").write_text(json.dumps(rows))
        return 0
    return report(rows, args)


def report(rows: list[dict], args) -> int:
    """Print and write the tables of ``rows``."""
    load = os.getloadavg()
    loads = sorted(r["load"] for r in rows)
    out = {"rows": rows, "load": load, "n_points": args.n_points, "summary": {}}
    lines = [
        "# Every reflection plane (issue 53)", "",
        f"{len(rows)} shapes at {args.n_points} surface samples; truth by geometry (exact <= {EXACT}, true <= {NEAR}, "
        f"distance ratio); 1-minute load average during the runs {loads[0]:.1f}-{loads[-1]:.1f} "
        f"(median {statistics.median(loads):.1f}) on 2 cores shared with other jobs (times scale with it).", "",
        "| part | method | shapes | precision | recall | count right | median s | p90 s | max s | median CPU s | p90 CPU s |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for part in ("choose", "report", "all"):
        sel = [r for r in rows if part == "all" or r["part"] == part]
        for key in ("planes", "one_plane"):
            s = summarise(sel, key)
            out["summary"][f"{part}/{key}"] = s
            lines.append(
                f"| {part} | {key.replace('_', ' ')} | {s['shapes']} | {s['precision']:.3f} | {s['recall']:.3f} | "
                f"{s['count_right']:.3f} | {s['median_s']:.2f} | {s['p90_s']:.2f} | {s['max_s']:.2f} | "
                f"{s['median_cpu_s']:.2f} | {s['p90_cpu_s']:.2f} |"
            )
    lines += ["", "Per variant (planes):", "", "| variant | part | shapes | precision | recall | count right |", "|---|---|---|---|---|---|"]
    for v in VARIANTS:
        for part in ("choose", "report"):
            sel = [r for r in rows if r["variant"] == v and r["part"] == part]
            s = summarise(sel, "planes")
            lines.append(f"| {v} | {part} | {s['shapes']} | {s['precision']:.3f} | {s['recall']:.3f} | {s['count_right']:.3f} |")
    lines += ["", "Per family (planes, both parts):", "", "| family | shapes | precision | recall | count right | median CPU s |", "|---|---|---|---|---|---|"]
    fams: dict[str, list] = {}
    for r in rows:
        fam = "CGAL mirrored" if r["shape"].endswith("_mirrored") else (
            "CGAL" if r["index"] >= 9 * args.n_shapes else r["shape"].rstrip("0123456789").split("_")[0].rstrip("0123456789"))
        fams.setdefault(fam, []).append(r)
    for fam, sel in fams.items():
        s = summarise(sel, "planes")
        lines.append(f"| {fam} | {s['shapes']} | {s['precision']:.3f} | {s['recall']:.3f} | {s['count_right']:.3f} | {s['median_cpu_s']:.2f} |")
    bad = [r for r in rows if not r["planes"]["count_right"]]
    lines += ["", "Shapes whose count is wrong (planes): " + ", ".join(
        f"{r['shape']} ({r['variant']}: {r['planes']['found']}/{r['planes']['must']} found, "
        f"{r['planes']['reported'] - r['planes']['true']} false)" for r in bad
    )]
    write_report(args.out, args.stem, "\n".join(lines) + "\n", out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
