"""Benchmark of intrinsic reflection symmetry on triangle meshes (thesis Sec. 6.3).

Front door: not ``torchsym.detect``; it calls ``intrinsic_symmetry`` on meshes it remeshes, twists or
holes in memory, and runs variants with stages off beside the defaults.

Runs, in one process and on the same inputs, torchsym's ``intrinsic_symmetry`` (Ch. 6)
and pyFM (PyPI ``pyfmaps``) as the peer: pyFM's orientation-reversing functional self-map
(``FunctionalMapping.fit(..., w_orient=1, orient_reversing=True)``) fitted on the same
eigenbasis (k = 13) and the same descriptors (HKS, 50 scales), converted to a point map
by pyFM itself. Data sets:

- ``synthetic``: meshes from ``../shared/data/meshes`` mirror-completed across their most
  symmetric coordinate plane (exact ground truth), then twisted by 22.5 degrees about
  their longest in-plane axis (nearly isometric, breaks the extrinsic symmetry);
- ``synthetic+holes``: the same with geodesic holes removing 10 % of the area;
- ``FAUST`` and ``TOSCA``: the remeshed (~5k vertices) shapes of
  ``llorz/SGA18_orientation_BCICP_dataset`` with their symmetric landmark ground truth
  (``corres/NAME.vts`` and ``corres/NAME.sym.vts``), read from ``--faust-tosca DIR`` (the
  folder holding ``FAUST/`` and ``TOSCA_Isometric/``, or its parent); not committed;
- ``FAUST+holes`` / ``TOSCA+holes``: every 4th shape with 10 % of its area removed;
- ``TOSCA-nonIso``: BCICP's TOSCA_nonIsometric shapes, never used to choose settings (held out);
- ``... full``: each of those shapes refined on its own surface to 20,000-50,000 irregular
  vertices, the ground truth carried exactly (``fine_meshes.py``, cached under ``--fine``).

Metrics (Sec. 6.3.2): correspondence rate (geodesic error below ``sqrt(area / 20 pi)``,
on the surface: edge paths straightened by FlipOut, :func:`torchsym.metrics.correspondence_rate`;
the rate along mesh edges alone, stricter, beside it), mesh rate (share of meshes above
75 %), the extremity rate (the correspondence rate on the ground-truth vertices in the top 5 %
by mean geodesic distance, :func:`torchsym.metrics.extremity_vertices`, chosen on the
remeshed shape and carried to the full-resolution one), median seconds per mesh with
the eigendecomposition alone beside it. A timing row runs the mirror-completed
``mannequin-devil`` (about 12,900 vertices) five times, exactly symmetric and twisted as in
the synthetic set (``--timing-only`` reruns just these rows).

    python benchmarks/bench_mesh.py [--faust-tosca DIR] [--step N] [--sets A,B] [--no-ablations] [--no-pyfm]
                                    [--tag TEXT] [--timing-only | --fine-timing-only]

Run from the repository root with ``PYTHONPATH=.`` so that this checkout's ``torchsym`` is imported.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import statistics
import time
from pathlib import Path

import numpy as np
import torch
from scipy.spatial import cKDTree

from torchsym.errors import InputValueError
from torchsym.io import read_mesh
from torchsym.mesh import (
    Mesh,
    face_areas,
    heat_kernel_signature,
    hks_times,
    intrinsic_symmetry,
    laplacian_eigen,
)
from torchsym.mesh.intrinsic import GeodesicProbe, IntrinsicSymmetrySettings
from torchsym.mesh.operators import edge_graph
from torchsym.mesh.synthetic import mirror_complete, punch_holes, twist
from torchsym.metrics.mesh import correspondence_rate, extremity_vertices, mesh_rate

from fine_meshes import extremity, fine_shape, load_fine  # noqa: E402 (benchmarks/ is on sys.path when run as a script)

log = logging.getLogger("bench_mesh")
HERE = Path(__file__).resolve().parent
SYNTHETIC = ["man", "mannequin-devil", "camel", "elephant", "cow", "bull", "lion", "dino", "elk",
             "homer", "triceratops", "pig"]


_DEFAULT_REFINE_K = IntrinsicSymmetrySettings().refine.n_eigen
_DEFAULT_POLISH_K = IntrinsicSymmetrySettings().polish.n_eigen


def most_symmetric_axis(v: np.ndarray) -> int:
    """The coordinate axis whose median plane mirrors the vertices closest onto themselves."""
    tree = cKDTree(v)
    errs = []
    for a in range(3):
        m = v.copy()
        m[:, a] = 2 * np.median(v[:, a]) - m[:, a]
        errs.append(tree.query(m)[0].mean())
    return int(np.argmin(errs))


def synthetic_meshes(folder: Path) -> list[tuple[str, Mesh, np.ndarray]]:
    out = []
    for name in SYNTHETIC:
        path = folder / f"{name}.off"
        if not path.is_file():
            continue
        mesh, gt = mirror_and_twist(read_mesh(path, dtype=torch.float64))
        out.append((name, mesh, gt, None))
    return out


def mirror_and_twist(mesh: Mesh) -> tuple[Mesh, np.ndarray]:
    """``mesh`` mirror-completed across its most symmetric coordinate plane, then twisted by
    22.5 degrees about its longest in-plane axis; and the exact symmetric map."""
    v = mesh.vertices.numpy()
    axis = most_symmetric_axis(v)
    normal = np.eye(3)[axis]
    sym, gt = mirror_complete(mesh, normal, float(np.median(v[:, axis])))
    extent = np.ptp(sym.vertices.numpy(), axis=0)
    extent[axis] = -1
    return twist(sym, math.pi / 8, axis=int(np.argmax(extent))), gt.numpy()


def bcicp_paths(root: Path, which: str, step: int) -> list[Path]:
    folder = next((p for p in (root / which / "vtx_5k", root / "Dataset" / which / "vtx_5k") if p.is_dir()), None)
    if folder is None:
        log.warning("no %s/vtx_5k under %s", which, root)
        return []
    return sorted(folder.glob("*.off"))[::step]


def faust_tosca(root: Path, which: str, step: int, cache: Path) -> list[tuple[str, Mesh, np.ndarray, np.ndarray]]:
    """The remeshed BCICP shapes, their ground truth ``(V,)`` and extremity landmarks (cached under ``cache``)."""
    out = []
    for path in bcicp_paths(root, which, step):
        corres = path.parent / "corres"
        src = np.loadtxt(corres / f"{path.stem}.vts", dtype=np.int64) - 1
        dst = np.loadtxt(corres / f"{path.stem}.sym.vts", dtype=np.int64) - 1
        mesh = read_mesh(path, dtype=torch.float64)
        gt = np.full(mesh.num_vertices, -1, dtype=np.int64)
        gt[src] = dst
        out.append((path.stem, mesh, gt, extremity(path, cache / which)))
    return out


def faust_tosca_fine(root: Path, which: str, step: int, cache: Path) -> list[tuple[str, Mesh, np.ndarray, np.ndarray]]:
    """Full-resolution irregular versions of the same shapes (``benchmarks/fine_meshes.py``, generated once into ``cache``)."""
    out = []
    for path in bcicp_paths(root, which, step):
        mesh, gt, coarse = load_fine(fine_shape(path, cache / which))
        out.append((path.stem, mesh, gt, coarse[extremity(path, cache / which)]))
    return out


def with_holes(items, seed: int = 0):
    out = []
    for i, (name, mesh, gt, _) in enumerate(items):
        holed, g = punch_holes(mesh, torch.from_numpy(gt), area_fraction=0.1,
                               generator=torch.Generator().manual_seed(seed + i))
        out.append((name, holed, g.numpy(), None))
    return out


def pyfm_map(mesh: Mesh) -> tuple[np.ndarray, float]:
    """pyFM's orientation-reversing self-map on our eigenbasis and HKS descriptors."""
    from pyFM.functional import FunctionalMapping
    from pyFM.mesh import TriMesh

    t0 = time.perf_counter()
    v = mesh.vertices.numpy()
    f = mesh.faces.numpy()
    v = (v - v.mean(0)) / math.sqrt(face_areas(v, f).sum())
    evals, evecs = laplacian_eigen(v, f, 13)
    hks = heat_kernel_signature(evals, evecs, hks_times(evals, 50))
    meshes = []
    for _ in range(2):
        tm = TriMesh(v, f)
        tm.compute_operators()
        tm.eigenvalues, tm.eigenvectors = evals.copy(), evecs.copy()
        meshes.append(tm)
    model = FunctionalMapping(meshes[0], meshes[1])
    model.add_descriptors(hks, hks)
    model.fit(K=(13, 13), w_descr=1e-1, w_lap=1e-3, w_dcomm=1, w_orient=1, orient_reversing=True)
    p2p = np.asarray(model.get_p2p(), dtype=np.int64)
    return p2p, time.perf_counter() - t0


def distortions(mesh: Mesh, predicted: np.ndarray, gt: np.ndarray, seed: int = 0) -> tuple[float, float, float]:
    """Geodesic distortion (mean relative error of 60 x 600 sampled edge-graph distances,
    :class:`~torchsym.mesh.intrinsic.GeodesicProbe`) of our map and of the ground-truth map,
    on the vertices where both are defined, and the share of 100 vertices that our map
    leaves within the correspondence tolerance of themselves. A method that seeks the most
    isometric involution cannot reach a ground truth that distorts more than its own map;
    a map that leaves most vertices in place is (partly) the identity, which distorts
    nothing and is no symmetry, so it does not count as such a case."""
    v, f = mesh.vertices.double().numpy(), mesh.faces.numpy()
    rows = np.flatnonzero((np.asarray(gt) >= 0) & (predicted >= 0))
    radius = math.sqrt(float(face_areas(v, f).sum()) / (20.0 * math.pi))
    probe = GeodesicProbe(edge_graph(v, f), rows, np.random.default_rng(seed), n_sources=60, n_targets=600, radius=radius)
    return probe.distortion(predicted[rows]), probe.distortion(np.asarray(gt)[rows]), probe.near_self(predicted[rows])


def extremity_rate(mesh: Mesh, predicted, gt: np.ndarray, ext: np.ndarray) -> float:
    """Correspondence rate on the extremity landmarks ``ext`` alone."""
    return correspondence_rate(mesh, predicted, landmarks=np.stack([ext, gt[ext]], axis=1)).rate


def _mean(rows: list[dict], key: str) -> float:
    return float(np.mean([r[key] for r in rows])) if rows else float("nan")


def _mesh_rate(rows: list[dict], key: str) -> float:
    return mesh_rate([r[key] for r in rows]) if rows else float("nan")


def evaluate(items, use_pyfm: bool, ablations: bool = True) -> dict:
    rows, skipped = [], []
    for name, mesh, gt, ext in items:
        if ext is None:
            ext = extremity_vertices(mesh, candidates=gt >= 0).numpy()
        try:
            res = intrinsic_symmetry(mesh)
        except InputValueError as exc:  # a broken input is reported, not scored
            log.warning("%s skipped: %s", name, exc)
            skipped.append(name)
            continue
        ours = correspondence_rate(mesh, res.map, ground_truth=gt).rate
        row = {"name": name, "vertices": mesh.num_vertices, "ours": ours, "time": res.timings["total"],
               "eigen": res.timings["eigen"], "pairs": int(res.pairs.shape[0]), "hypothesis": res.hypothesis,
               "ours_ext": extremity_rate(mesh, res.map, gt, ext), "n_ext": int(ext.size)}
        if use_pyfm:
            p2p, t = pyfm_map(mesh)
            row["pyfm"] = correspondence_rate(mesh, p2p, ground_truth=gt).rate
            row["pyfm_ext"] = extremity_rate(mesh, p2p, gt, ext)
            row["pyfm_time"] = t
        if not ablations:  # the dev protocol: no stricter edge-path rate either
            log.info("%s", {k: (round(x, 3) if isinstance(x, float) else x) for k, x in row.items()})
            rows.append(row)
            continue
        row["ours_edges"] = correspondence_rate(mesh, res.map, ground_truth=gt, geodesics="edges").rate
        if use_pyfm:
            row["pyfm_edges"] = correspondence_rate(mesh, p2p, ground_truth=gt, geodesics="edges").rate
        # ablation: the same solver without the orientation-reversing and extrinsic hypotheses
        pairs_only = intrinsic_symmetry(mesh, hypotheses={"orientation": False}, extrinsic={"enabled": False})
        row["pairs_only"] = correspondence_rate(mesh, pairs_only.map, ground_truth=gt).rate
        # ablation: without the extrinsic hypothesis (the same map where it was not chosen)
        row["no_extrinsic"] = ours
        if res.hypothesis == "extrinsic":
            row["no_extrinsic"] = correspondence_rate(
                mesh, intrinsic_symmetry(mesh, extrinsic={"enabled": False}).map, ground_truth=gt
            ).rate
        # ablation: without the orientation check (the same map where it did not re-refine)
        row["reoriented"] = any("with the orientation penalty, it reverses" in n for n in res.notes)
        row["no_orientation_check"] = ours
        if row["reoriented"]:
            row["no_orientation_check"] = correspondence_rate(
                mesh, intrinsic_symmetry(mesh, refine={"orientation_weight": 0.0}).map, ground_truth=gt
            ).rate
        # ablation: without step 13, the polish to polish.n_eigen eigenfunctions (the same map where it was not kept)
        row["polished"] = int(res.refined_functional_map.shape[0]) > _DEFAULT_REFINE_K
        row["no_polish"] = ours
        if row["polished"]:
            row["no_polish"] = correspondence_rate(mesh, intrinsic_symmetry(mesh, polish={"enabled": False}).map, ground_truth=gt).rate
        # ablation: without step 14, the realignment by distances to anchors (the same map where it was not kept)
        row["realigned"] = any(n.startswith("realigned by") for n in res.notes)
        row["no_realign"] = ours
        if row["realigned"]:
            row["no_realign"] = correspondence_rate(mesh, intrinsic_symmetry(mesh, realign={"enabled": False}).map, ground_truth=gt).rate
        # ablation: without closing the holes first (the same map on a closed mesh)
        row["holes_closed"] = res.holes_closed
        row["no_fill"] = ours
        if res.holes_closed:
            row["no_fill"] = correspondence_rate(mesh, intrinsic_symmetry(mesh, fill_holes=False).map, ground_truth=gt).rate
        if ours <= 0.75:  # a failed mesh: is the ground truth itself the more isometric map?
            row["distortion_ours"], row["distortion_truth"], row["near_self"] = distortions(mesh, res.map.numpy(), gt)
        log.info("%s", {k: (round(x, 3) if isinstance(x, float) else x) for k, x in row.items()})
        rows.append(row)
    summary = {
        "meshes": len(rows),
        "skipped": skipped,
        "vertices_median": statistics.median(r["vertices"] for r in rows) if rows else float("nan"),
        "ours_rate": _mean(rows, "ours"),
        "ours_mesh_rate": _mesh_rate(rows, "ours"),
        "ours_ext_rate": _mean(rows, "ours_ext"),
        "ours_ext_mesh_rate": _mesh_rate(rows, "ours_ext"),
        "ours_median_time": statistics.median(r["time"] for r in rows) if rows else float("nan"),
        "ours_max_time": max((r["time"] for r in rows), default=float("nan")),
        "eigen_median_time": statistics.median(r["eigen"] for r in rows) if rows else float("nan"),
    }
    if ablations and rows:
        summary.update({
            "ours_edges_rate": _mean(rows, "ours_edges"),
            "ours_edges_mesh_rate": _mesh_rate(rows, "ours_edges"),
            "pairs_only_rate": _mean(rows, "pairs_only"),
            "no_fill_rate": _mean(rows, "no_fill"),
            "holes_closed": sum(r["holes_closed"] > 0 for r in rows),
            "orientation_chosen": sum(r["hypothesis"] == "orientation" for r in rows),
            "no_extrinsic_rate": _mean(rows, "no_extrinsic"),
            "extrinsic_chosen": sum(r["hypothesis"] == "extrinsic" for r in rows),
            "no_orientation_check_rate": _mean(rows, "no_orientation_check"),
            "no_orientation_check_mesh_rate": _mesh_rate(rows, "no_orientation_check"),
            "reoriented": sum(r["reoriented"] for r in rows),
            "no_polish_rate": _mean(rows, "no_polish"),
            "no_polish_mesh_rate": _mesh_rate(rows, "no_polish"),
            "polished": sum(r["polished"] for r in rows),
            "no_realign_rate": _mean(rows, "no_realign"),
            "no_realign_mesh_rate": _mesh_rate(rows, "no_realign"),
            "realigned": sum(r["realigned"] for r in rows),
            "failed": sum("distortion_ours" in r for r in rows),
            "failed_truth_less_isometric": sum(
                r["distortion_truth"] > r["distortion_ours"] and r["near_self"] < 0.6 for r in rows if "near_self" in r
            ),
        })
    if use_pyfm and rows:
        summary.update(
            pyfm_rate=_mean(rows, "pyfm"),
            pyfm_mesh_rate=_mesh_rate(rows, "pyfm"),
            pyfm_ext_rate=_mean(rows, "pyfm_ext"),
            pyfm_edges_rate=_mean(rows, "pyfm_edges") if ablations else float("nan"),
            pyfm_median_time=statistics.median(r["pyfm_time"] for r in rows),
        )
    return {"summary": summary, "rows": rows}


def timing_row(folder: Path, reps: int = 7) -> dict:
    """Median times of ``reps`` runs on the mirror-completed ``mannequin-devil`` (exactly symmetric)
    and, under ``"bent"``, on the same mesh twisted as in the synthetic set (nearly isometric).

    The floor is the eigendecomposition alone (:func:`laplacian_eigen` with the solver's
    ``polish.n_eigen`` eigenpairs), timed on its own after each run: inside the solver the
    non-spectral work runs beside it on the second core, which slows it slightly.
    """
    path = folder / "mannequin-devil.off"
    if not path.is_file():
        return {}
    original = read_mesh(path, dtype=torch.float64)
    exact, _ = mirror_complete(original)
    bent, _ = mirror_and_twist(original)
    rows = {}
    for label, mesh in (("exact", exact), ("bent", bent)):
        v, f = mesh.vertices.double().numpy(), mesh.faces.numpy()
        intrinsic_symmetry(mesh)  # warm-up
        runs, floor = [], []
        for _ in range(reps):  # the solver and its eigendecomposition alone, one after the other
            runs.append(intrinsic_symmetry(mesh).timings)
            tic = time.perf_counter()
            laplacian_eigen(v, f, _DEFAULT_POLISH_K, generator=torch.Generator().manual_seed(0))
            floor.append(time.perf_counter() - tic)
        stages = {k: statistics.median(t.get(k, 0.0) for t in runs) for k in runs[0] if k != "total"}
        total, eigen = statistics.median(t["total"] for t in runs), statistics.median(floor)
        rows[label] = {"vertices": mesh.num_vertices, "median_total": total, "median_eigen": eigen,
                       "ratio": total / eigen, "stages": stages}
    return {**rows["exact"], "bent": rows["bent"]}


def fine_timing_row(items, reps: int = 3) -> dict:
    """Median time of ``reps`` runs on the largest full-resolution shape of ``items``, against the
    eigendecomposition alone of the full mesh (``polish.n_eigen`` eigenpairs, what solving it
    directly would need), timed on its own after each run."""
    if not items:
        return {}
    name, mesh, _, _ = max(items, key=lambda it: it[1].num_vertices)
    v, f = mesh.vertices.double().numpy(), mesh.faces.numpy()
    intrinsic_symmetry(mesh)  # warm-up
    runs, floor, cpu, cpu_floor = [], [], [], []
    for _ in range(reps):
        c0 = time.process_time()
        runs.append(intrinsic_symmetry(mesh).timings)
        c1 = time.process_time()
        tic = time.perf_counter()
        laplacian_eigen(v, f, _DEFAULT_POLISH_K, generator=torch.Generator().manual_seed(0))
        floor.append(time.perf_counter() - tic)
        cpu.append(c1 - c0)
        cpu_floor.append(time.process_time() - c1)
    total, eigen = statistics.median(t["total"] for t in runs), statistics.median(floor)
    return {"name": name, "vertices": mesh.num_vertices, "reps": reps, "median_total": total, "median_eigen": eigen,
            "median_cpu": statistics.median(cpu), "median_eigen_cpu": statistics.median(cpu_floor),
            "ratio": total / eigen, "coarsen": statistics.median(t.get("coarsen", 0.0) for t in runs),
            "carry": statistics.median(t.get("carry", 0.0) for t in runs)}


def fmt(x: float, pct: bool = False) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return f"{100 * x:.1f}" if pct else f"{x:.2f}"


def _table(results: dict, key: str, cells) -> list[str]:
    """One table row per data set whose summary has ``key``."""
    return [cells(name, res["summary"]) for name, res in results.items() if key in res["summary"]]


def _dev_cells(name: str, s: dict) -> str:
    return (
        f"| {name} | {s['meshes']} | {s.get('vertices_median', float('nan')):.0f} | {fmt(s['ours_rate'], True)} | "
        f"{fmt(s['ours_ext_rate'], True)} | {fmt(s['ours_mesh_rate'], True)} | "
        f"{fmt(s['ours_median_time'])} ({fmt(s.get('ours_max_time', float('nan')))}) | "
        f"{fmt(s.get('pyfm_rate', float('nan')), True)} | {fmt(s.get('pyfm_ext_rate', float('nan')), True)} | "
        f"{fmt(s.get('pyfm_mesh_rate', float('nan')), True)} | {fmt(s.get('pyfm_median_time', float('nan')))} |"
    )


def _ablation_cells(name: str, s: dict) -> str:
    return (
        f"| {name} | {s['meshes']} | {fmt(s['ours_rate'], True)} | {fmt(s['ours_mesh_rate'], True)} | "
        f"{fmt(s.get('ours_edges_rate', float('nan')), True)} / {fmt(s.get('ours_edges_mesh_rate', float('nan')), True)} | "
        f"{s.get('failed', '-')} ({s.get('failed_truth_less_isometric', '-')}) | "
        f"{fmt(s.get('pairs_only_rate', float('nan')), True)} | {s.get('orientation_chosen', '-')} | "
        f"{fmt(s.get('no_extrinsic_rate', float('nan')), True)} ({s.get('extrinsic_chosen', '-')}) | "
        f"{fmt(s.get('no_fill_rate', float('nan')), True)} ({s.get('holes_closed', '-')}) | "
        f"{fmt(s.get('no_orientation_check_rate', float('nan')), True)} / "
        f"{fmt(s.get('no_orientation_check_mesh_rate', float('nan')), True)} ({s.get('reoriented', '-')}) | "
        f"{fmt(s.get('no_polish_rate', float('nan')), True)} / "
        f"{fmt(s.get('no_polish_mesh_rate', float('nan')), True)} ({s.get('polished', '-')}) | "
        f"{fmt(s.get('no_realign_rate', float('nan')), True)} / "
        f"{fmt(s.get('no_realign_mesh_rate', float('nan')), True)} ({s.get('realigned', '-')}) | "
        f"{fmt(s.get('pyfm_rate', float('nan')), True)} ({fmt(s.get('pyfm_edges_rate', float('nan')), True)}) | "
        f"{fmt(s.get('pyfm_mesh_rate', float('nan')), True)} | "
        f"{fmt(s['ours_median_time'])} | {fmt(s['eigen_median_time'])} | {fmt(s.get('pyfm_median_time', float('nan')))} |"
    )


def render_dev(results: dict, fine_timing: dict) -> list[str]:
    """The dev protocol of issue 33: all-vertex and extremity rates at both resolutions, beside pyFM."""
    lines = [
        "## Dev protocol: every vertex and the extremities, remeshed and full resolution",
        "",
        (
            "Extremity rate: the correspondence rate on the ground-truth vertices in the top 5 % by mean "
            "geodesic distance to the rest of the shape (`torchsym.metrics.extremity_vertices`, 128 "
            "farthest-point sources weighted by their Voronoi cells' areas; limb, head and tail ends; for FAUST/TOSCA chosen on the remeshed shape and "
            "carried to the full-resolution one). Full resolution: each remeshed BCICP shape refined on its own "
            "surface to 20,000-50,000 irregular vertices (`benchmarks/fine_meshes.py`: midpoint subdivision at "
            "random edge points, random faces split at random interior points, vertices shuffled), ground truth "
            "carried exactly. Mesh rate on the all-vertex rate (> 75 %). Times: seconds per mesh on 2 cores "
            "shared with many other jobs (load 10-18): wall-clock times are noisy and several times an idle machine's; "
            "the full-resolution timing also gives processor time."
        ),
        "",
        "| data set | meshes | median vertices | torchsym rate % | extremity rate % | mesh rate % "
        "| median s (max) | pyFM rate % | pyFM extremity rate % | pyFM mesh rate % | pyFM median s |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    lines += _table(results, "ours_ext_rate", _dev_cells)
    if fine_timing:
        t = fine_timing
        lines += [
            "",
            (
                f"Timing at full resolution ({t['name']}, {t['vertices']} vertices, median of {t['reps']}): total "
                f"{t['median_total']:.2f} s (decimation {t['coarsen']:.2f} s, carrying the map {t['carry']:.2f} s), "
                f"its eigendecomposition alone ({_DEFAULT_POLISH_K} eigenpairs of the full mesh) {t['median_eigen']:.2f} s, "
                f"ratio {t['ratio']:.2f}x; processor time (all threads, less sensitive to the other jobs) "
                f"{t.get('median_cpu', float('nan')):.2f} s against {t.get('median_eigen_cpu', float('nan')):.2f} s."
            ),
        ]
    return lines + [""]


def render(results: dict, timing: dict, fine_timing: dict | None = None) -> str:
    """The Markdown report of a run."""
    lines = [
        "# Intrinsic reflection symmetry on meshes (thesis Sec. 6.3)",
        "",
        *render_dev(results, fine_timing or {}),
        "## All sets, with ablations",
        "",
        (
            "Correspondence rate: share of ground-truth correspondences whose predicted symmetric vertex "
            "lies within sqrt(area / 20 pi) of the true one, geodesic distance on the surface (the shortest "
            "edge path straightened across the faces by potpourri3d's FlipOut; 'along edges': the edge path "
            "alone, which over-estimates the surface distance by a median 8 % near the tolerance), over every ground-truth vertex (dense: ~5,000 template landmarks on "
            "FAUST/TOSCA, every vertex on the synthetic meshes; the thesis scored ~20 landmarks per "
            "shape); mesh rate: share of meshes with a rate above 75 %. Holes: 3 geodesic discs "
            "removing 10 % of the area at random (asymmetric) places, largest component kept. Peer: "
            "pyFM orientation-reversing self-map on the same eigenbasis (k = 13) and HKS descriptors "
            "(50 scales). Ablations: torchsym without the orientation-reversing and extrinsic hypotheses (only the "
            "thesis's pairings), and how often the orientation-reversing one was chosen; torchsym without the "
            "extrinsic hypothesis (the vertices' mirror plane, tried when the intrinsic ones are weak), and how "
            "often it was chosen; torchsym without closing "
            "the holes first (`fill_holes=False`; the same run on meshes without holes), and on how "
            "many meshes holes were closed; torchsym without the orientation check of its final map "
            "(`refine.orientation_weight=0`), and on how many meshes that check refined the map again (or rescued it where no hypothesis passed); torchsym without step 13, the polish from 25 to 40 "
            "eigenfunctions (`polish.enabled=false`), and on how many meshes the polished map was kept; torchsym without "
            "step 14, the realignment by distances to anchors (`realign.enabled=false`), and on how many meshes the "
            "realigned map was kept. Failed: meshes at or below "
            "75 %, and on how many of them the ground-truth map distorts geodesics more than ours "
            "(mean relative error of 60 x 600 sampled distances) while ours is no partial identity "
            "(under 60 % of 100 vertices left within the tolerance of themselves): there the ground "
            "truth is not the most isometric involution that an intrinsic method looks for. Times: seconds per mesh "
            "on a 2-core CPU shared with other jobs."
        ),
        "",
        (
            "| data set | meshes | torchsym rate % | torchsym mesh rate % | along edges: rate % / mesh rate % "
            "| failed (truth less isometric) "
            "| pairs only rate % | orientation chosen | without extrinsic rate % (extrinsic chosen) "
            "| without hole filling rate % (meshes filled) "
            "| without orientation check rate % / mesh rate % (re-refined) "
            "| without polish rate % / mesh rate % (polished) "
            "| without realign rate % / mesh rate % (realigned) "
            "| pyFM rate % (along edges) | pyFM mesh rate % | torchsym median s | eigendecomposition median s | pyFM median s |"
        ),
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    lines += _table(results, "pairs_only_rate", _ablation_cells)
    if timing:
        lines += [
            "",
            (
                f"Timing ({timing['vertices']} vertices, mirror-completed mannequin-devil, median of 7): "
                f"total {timing['median_total']:.2f} s, eigendecomposition alone {timing['median_eigen']:.2f} s "
                f"(the solver's {_DEFAULT_POLISH_K} eigenpairs, timed on its own after each run), "
                f"ratio {timing['ratio']:.2f}x. The thesis's own map (`map_before_refine`), where ZoomOut's "
                "map replaced it, is searched when first read, outside these times."
            ),
        ]
        if "bent" in timing:
            b = timing["bent"]
            lines += [
                "",
                (
                    f"The same mesh twisted as in the synthetic set ({b['vertices']} vertices, nearly isometric): "
                    f"total {b['median_total']:.2f} s, eigendecomposition alone {b['median_eigen']:.2f} s, ratio "
                    f"{b['ratio']:.2f}x. Largest stages (median s, twisted / exact; stages on threads each "
                    "count their own time): "
                    + ", ".join(f"{k} {v:.2f} / {timing.get('stages', {}).get(k, float('nan')):.2f}"
                                for k, v in sorted(b.get("stages", {}).items(), key=lambda kv: -kv[1])[:4])
                    + "."
                ),
            ]
    return "\n".join(lines) + "\n"


SET_NAMES = ("synthetic", "synthetic+holes", "FAUST", "FAUST+holes", "TOSCA", "TOSCA+holes", "FAUST full", "TOSCA full",
             "TOSCA-nonIso", "TOSCA-nonIso full")
BCICP = (("FAUST", "FAUST"), ("TOSCA_Isometric", "TOSCA"), ("TOSCA_nonIsometric", "TOSCA-nonIso"))


def _set_index(label: str) -> int:
    """Position in SET_NAMES of the data set a (tagged) result label names."""
    names = sorted(range(len(SET_NAMES)), key=lambda i: -len(SET_NAMES[i]))
    return next((i for i in names if label.startswith(SET_NAMES[i])), len(SET_NAMES))


def build_sets(args) -> dict[str, list]:
    """The data sets asked for by ``--sets`` (all that the given folders hold by default)."""
    wanted = set(args.sets.split(",")) if args.sets else set(SET_NAMES)
    sets: dict[str, list] = {}
    if args.meshes.is_dir() and wanted & {"synthetic", "synthetic+holes"}:
        synth = synthetic_meshes(args.meshes)
        sets["synthetic"] = synth
        sets["synthetic+holes"] = with_holes(synth)
    if args.faust_tosca is not None:
        for which, label in BCICP:
            if wanted & {label, f"{label}+holes"}:
                items = faust_tosca(args.faust_tosca, which, args.step, args.fine)
                if items:
                    sets[label] = items
                    if label != "TOSCA-nonIso":  # held out: not used to choose settings, no holed variant
                        sets[f"{label}+holes"] = with_holes(items[::4], seed=100)
            if f"{label} full" in wanted:
                sets[f"{label} full"] = faust_tosca_fine(args.faust_tosca, which, args.step * args.fine_step, args.fine)
    return {k: v for k, v in sets.items() if k in wanted and v}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--faust-tosca", type=Path, default=None, help="folder with FAUST/ and TOSCA_Isometric/")
    ap.add_argument("--fine", type=Path, default=Path("/work/data/bcicp_fine"),
                    help="cache of the full-resolution shapes and extremity landmarks (generated when missing)")
    ap.add_argument("--meshes", type=Path, default=HERE.parent.parent / "shared" / "data" / "meshes")
    ap.add_argument("--step", type=int, default=1, help="use every N-th FAUST/TOSCA shape")
    ap.add_argument("--fine-step", type=int, default=1, help="of those, every N-th at full resolution")
    ap.add_argument("--sets", default="", help=f"comma-separated subset of {', '.join(SET_NAMES)}; saved results "
                    "of the other sets are kept")
    ap.add_argument("--no-pyfm", action="store_true", help="skip the pyFM peer")
    ap.add_argument("--no-ablations", action="store_true", help="skip the ablation runs (on the full-resolution sets always)")
    ap.add_argument("--tag", default="", help="appended to the data sets' names in the results (e.g. ', every 20th')")
    ap.add_argument("--out", type=Path, default=HERE / "results")
    ap.add_argument("--render-only", action="store_true", help="rewrite mesh.md from an existing mesh.json")
    ap.add_argument("--timing-only", action="store_true",
                    help="rerun only the timing rows and rewrite mesh.md / mesh.json, keeping the saved accuracy results")
    ap.add_argument("--fine-timing-only", action="store_true",
                    help="rerun only the full-resolution timing row (needs --faust-tosca), keeping the rest")
    args = ap.parse_args(argv)
    saved_path = args.out / "mesh.json"
    saved = json.loads(saved_path.read_text()) if saved_path.is_file() else {"results": {}, "timing": {}}
    if args.fine_timing_only and args.faust_tosca is not None:
        torch.set_num_threads(min(2, torch.get_num_threads()))
        saved["fine_timing"] = fine_timing_row(faust_tosca_fine(args.faust_tosca, "TOSCA_Isometric", 1, args.fine))
        saved_path.write_text(json.dumps(saved, indent=2))
        args.render_only = True
    if args.render_only or args.timing_only:
        if not saved_path.is_file():
            ap.error(f"--render-only / --timing-only need a saved {saved_path}; run the full benchmark first")
        if args.timing_only:
            torch.set_num_threads(min(2, torch.get_num_threads()))
            saved["timing"] = timing_row(args.meshes)
            if args.faust_tosca is not None:
                saved["fine_timing"] = fine_timing_row(faust_tosca_fine(args.faust_tosca, "TOSCA_Isometric", 1, args.fine))
            saved_path.write_text(json.dumps(saved, indent=2))
        text = render(saved["results"], saved["timing"], saved.get("fine_timing"))
        print(text)
        (args.out / "mesh.md").write_text(text)
        return
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    torch.set_num_threads(min(2, torch.get_num_threads()))
    use_pyfm = not args.no_pyfm
    if use_pyfm:
        try:
            import pyFM  # noqa: F401
        except ImportError:
            log.warning("pyFM (pip install pyfmaps) is not installed; running without the peer")
            use_pyfm = False

    sets = build_sets(args)
    args.out.mkdir(parents=True, exist_ok=True)
    results = {}
    for name, items in sets.items():  # saved after each set, so that a stopped run keeps what it finished
        results[name + args.tag] = evaluate(items, use_pyfm, ablations=not args.no_ablations and "full" not in name)
        saved_path.write_text(json.dumps({**saved, "results": {**saved["results"], **results}}, indent=2))
    if not args.sets:
        saved["timing"] = timing_row(args.meshes) if args.meshes.is_dir() else {}
        if args.faust_tosca is not None:
            saved["fine_timing"] = fine_timing_row(faust_tosca_fine(args.faust_tosca, "TOSCA_Isometric", 1, args.fine))
    merged = {**saved["results"], **results}
    merged = dict(sorted(merged.items(), key=lambda kv: (_set_index(kv[0]), kv[0])))
    saved["results"] = merged
    text = render(merged, saved["timing"], saved.get("fine_timing"))
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "mesh.md").write_text(text)
    saved_path.write_text(json.dumps(saved, indent=2))


if __name__ == "__main__":
    main()
