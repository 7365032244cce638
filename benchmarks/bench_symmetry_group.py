"""The whole symmetry group of a shape: n-fold axes found directly (chiral shapes with no
plane too), the whole group, false symmetry on asymmetric shapes, time (issue 58).

Shapes, each built in code with a known point group, scaled to a unit diagonal, moved by
a random rigid motion and sampled at ``--n-points`` surface points as it comes in turn:
clean, with Gaussian noise (0.3 % of the diagonal), with three holes (2 % of the points
each) or with the density falling to 40 % along a random direction
(``bench_planes.variant_points``):

* ``chiral``: a real part (the faces of a CGAL mesh within a ball about a random vertex,
  scaled to 0.4 and set 0.7 off the axis) repeated ``n`` times about the axis: C_n, no
  plane; ``n = 2 .. 12``;
* ``achiral``: the same part and its mirror image, ``n`` times: C_nv (``n`` planes);
* ``fan`` (pitched blades: D_n, no plane), ``gear`` (D_nh), ``bolt`` (hexagonal or other
  head on a round shaft: C_nv), ``wheel`` (rim band, hub, spokes: D_nh);
* ``revolution``: cylinders and cones (an axis of revolution);
* ``asymmetric``: a real part alone (no symmetry expected).

Figures: *axis and order right* (the true n-fold axis among the group's axes within 5
degrees, with order n; for revolution: the axis of revolution within 5 degrees); *whole
group right* (the group's order, its number of planes and its axes' orders all as
built; for revolution: one axis of revolution); *no false symmetry* (asymmetric: the
group is the identity alone); median seconds per shape (wall, on a shared 2-core machine,
torch threads 1; the load is printed).

Run: ``PYTHONPATH=. python benchmarks/bench_symmetry_group.py`` (results in
``benchmarks/results/symmetry_group.md`` and ``.json``).
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))

import torchsym  # noqa: E402
from bench_planes import VARIANTS, variant_points  # noqa: E402
from report import write_report  # noqa: E402
from torchsym.geometry.mesh import Mesh  # noqa: E402
from torchsym.manifolds.special_orthogonal import SpecialOrthogonal  # noqa: E402
from torchsym.pointcloud import cone_mesh, prism_mesh  # noqa: E402
from torchsym.pointcloud.rotational_shapes import about_axis, bolt_mesh, fan_mesh, gear_mesh, spoked_wheel_mesh  # noqa: E402


def real_part(mesh: Mesh, g: torch.Generator) -> Mesh:
    """The faces of ``mesh`` within a ball (a quarter of the diagonal) about a random
    vertex, scaled to a 0.4 diagonal and set 0.7 off the z axis along x."""
    v = mesh.vertices.double()
    v = (v - v.mean(0)) / float((v.max(0).values - v.min(0).values).norm())
    c = v[int(torch.randint(0, v.shape[0], (1,), generator=g))]
    inside = (v - c).norm(dim=1) < 0.25
    faces = mesh.faces[inside[mesh.faces].all(1)]
    used = torch.unique(faces)
    remap = torch.full((v.shape[0],), -1, dtype=torch.int64)
    remap[used] = torch.arange(used.numel())
    pv = v[used]
    pv = (pv - pv.mean(0)) * (0.4 / float((pv.max(0).values - pv.min(0).values).norm()))
    return Mesh(pv + torch.tensor([0.7, 0.0, 0.0], dtype=torch.float64), remap[faces])


def make_shapes(data: Path, seed: int) -> list[tuple[str, str, Mesh, dict]]:
    """``(family, name, mesh, truth)``: truth has ``order`` (the group's), ``planes``,
    ``orders`` (sorted axis orders), ``n`` (the main axis's order; 0 for revolution)."""
    g = torch.Generator().manual_seed(seed)
    meshes = [torchsym.io.read_mesh(p, dtype=torch.float64) for p in sorted(data.glob("*.off"))]
    out = []
    for n in range(2, 13):
        m = meshes[n % len(meshes)]
        part = real_part(m, g)
        out.append(("chiral", f"chiral{n}", about_axis(part, n), dict(order=n, planes=0, orders=[n], n=n)))
        part = real_part(meshes[(n + 5) % len(meshes)], g)
        out.append(("achiral", f"achiral{n}", about_axis(part, n, mirror=True), dict(order=2 * n, planes=n, orders=[n], n=n)))
    for n in (2, 3, 4, 5, 6, 8, 12):
        orders = [2, 2, 2] if n == 2 else sorted([2] * n + [n])
        out.append(("fan", f"fan{n}", fan_mesh(n, pitch=0.3 + 0.05 * n), dict(order=2 * n, planes=0, orders=orders, n=n)))
    for n in (3, 5, 8, 10, 12):
        out.append(("gear", f"gear{n}", gear_mesh(n), dict(order=4 * n, planes=n + 1, orders=sorted([2] * n + [n]), n=n)))
    for n in (4, 6, 8):
        out.append(("bolt", f"bolt{n}", bolt_mesh(n), dict(order=2 * n, planes=n, orders=[n], n=n)))
    for n in (3, 4, 5, 6):
        orders = sorted([2] * n + [n]) if n > 2 else [2, 2, 2]
        out.append(("wheel", f"wheel{n}", spoked_wheel_mesh(n), dict(order=4 * n, planes=n + 1, orders=orders, n=n)))
    for k, h in enumerate((0.6, 1.5, 2.5)):
        out.append(("revolution", f"cylinder{k}", prism_mesh(256, 1.0, h), dict(order=0, planes=0, orders=[], n=0)))
    for k, h in enumerate((0.8, 1.6)):
        out.append(("revolution", f"cone{k}", cone_mesh(256, 1.0, h), dict(order=0, planes=0, orders=[], n=0)))
    for k in range(10):
        part = real_part(meshes[k % len(meshes)], g)
        out.append(("asymmetric", f"part{k}", part, dict(order=1, planes=0, orders=[], n=1)))
    return out


def posed(mesh: Mesh, g: torch.Generator) -> tuple[Mesh, torch.Tensor]:
    """``mesh`` scaled to a unit diagonal about its axis (z through the origin) and moved
    by a random rotation and translation; the axis's new direction."""
    v = mesh.vertices.double()
    v = v / float((v.max(0).values - v.min(0).values).norm())
    rot = SpecialOrthogonal(3).random_point(generator=g).double()
    return Mesh(v @ rot.T + torch.randn(3, generator=g, dtype=torch.float64), mesh.faces), rot[:, 2]


def judge(res, truth: dict, axis: torch.Tensor) -> dict:
    """The figures of one result against its truth."""
    grp = res.group
    cos5 = math.cos(math.radians(5.0))
    orders = sorted(int(o) for o in grp.orders)
    planes = int(grp.reflections.shape[0])
    if truth["n"] == 0:
        ok_axis = any(float((d.double() @ axis).abs()) > cos5 for d in grp.continuous_axes)
        whole = ok_axis and grp.continuous_axes.shape[0] == 1
    elif truth["n"] == 1:
        ok_axis = whole = grp.order == 1
    else:
        ok_axis = any(float((d.double() @ axis).abs()) > cos5 and int(o) == truth["n"] for d, o in zip(grp.axes, grp.orders))
        whole = grp.closed and grp.order == truth["order"] and planes == truth["planes"] and orders == truth["orders"] \
            and grp.continuous_axes.shape[0] == 0
    return {"axis_ok": bool(ok_axis), "whole_ok": bool(whole), "group_order": grp.order, "planes": planes,
            "orders": orders, "continuous": int(grp.continuous_axes.shape[0]), "closed": bool(grp.closed)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default=str(Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "meshes"))
    ap.add_argument("--n-points", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=58)
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results"))
    ap.add_argument("--stem", default="symmetry_group")
    ap.add_argument("--only", default=None, help="comma-separated families to run")
    args = ap.parse_args(argv)
    torch.set_num_threads(1)
    cfg = Path(__file__).resolve().parents[1] / "configs" / "pointcloud_symmetry.yaml"
    rows = []
    for idx, (family, name, mesh, truth) in enumerate(make_shapes(Path(args.data), args.seed)):
        if args.only and family not in args.only.split(","):
            continue
        g = torch.Generator().manual_seed(args.seed * 7919 + idx)
        mesh, axis = posed(mesh, g)
        variant = VARIANTS[idx % len(VARIANTS)]
        pts = variant_points(mesh, variant, args.n_points, g).float()
        t0 = time.perf_counter()
        res = torchsym.detect(pts, cfg)
        sec = time.perf_counter() - t0
        row = {"index": idx, "family": family, "shape": name, "variant": variant, "truth": truth,
               **judge(res, truth, axis), "seconds": sec, "load": os.getloadavg()[0]}
        rows.append(row)
        print(f"{idx:3d} {family:10s} {name:12s} {variant:7s} axis {'OK ' if row['axis_ok'] else 'BAD'} "
              f"group {'OK ' if row['whole_ok'] else 'BAD'} order {row['group_order']} (want {truth['order']}) "
              f"planes {row['planes']} (want {truth['planes']}) orders {row['orders']} cont {row['continuous']} "
              f"{sec:.2f}s load {row['load']:.1f}", flush=True)
    return report(rows, args)


def report(rows: list[dict], args) -> int:
    """Print and write the table of ``rows``."""
    loads = sorted(r["load"] for r in rows)
    fams = ["chiral", "achiral", "fan", "gear", "bolt", "wheel", "revolution", "asymmetric"]
    lines = [
        "# The whole symmetry group (issue 58)", "",
        f"{len(rows)} shapes at {args.n_points} surface samples, each in a random pose, variants cycling "
        f"{', '.join(VARIANTS)}; `configs/pointcloud_symmetry.yaml` through `torchsym.detect`; wall seconds with torch "
        f"threads 1 on a shared 2-core machine, 1-minute load {loads[0]:.1f}-{loads[-1]:.1f}.", "",
        "| family | shapes | axis and order right | whole group right | median s | max s |",
        "|---|---|---|---|---|---|",
    ]
    summary = {}
    for fam in fams + ["all"]:
        rs = [r for r in rows if fam == "all" or r["family"] == fam]
        if not rs:
            continue
        s = {"n": len(rs), "axis": sum(r["axis_ok"] for r in rs) / len(rs), "whole": sum(r["whole_ok"] for r in rs) / len(rs),
             "median_s": statistics.median(r["seconds"] for r in rs), "max_s": max(r["seconds"] for r in rs)}
        summary[fam] = s
        label = "asymmetric (no false symmetry)" if fam == "asymmetric" else fam
        lines.append(f"| {label} | {s['n']} | {s['axis']:.0%} | {s['whole']:.0%} | {s['median_s']:.2f} | {s['max_s']:.2f} |")
    lines += ["", "By variant (all families):", "", "| variant | shapes | axis right | group right |", "|---|---|---|---|"]
    for v in VARIANTS:
        rs = [r for r in rows if r["variant"] == v]
        if rs:
            lines.append(f"| {v} | {len(rs)} | {sum(r['axis_ok'] for r in rs) / len(rs):.0%} | {sum(r['whole_ok'] for r in rs) / len(rs):.0%} |")
    bad = [r for r in rows if not (r["axis_ok"] and r["whole_ok"])]
    lines += ["", "Misses:", ""] + [
        f"- {r['shape']} ({r['variant']}): order {r['group_order']} (want {r['truth']['order']}), planes {r['planes']} "
        f"(want {r['truth']['planes']}), orders {r['orders']} (want {r['truth']['orders']}), continuous {r['continuous']}"
        for r in bad
    ]
    write_report(args.out, args.stem, "\n".join(lines) + "\n", {"rows": rows, "summary": summary})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
