"""The oracle of step 9 on SHREC'07 (issue 57): is the right map among the hypotheses, and is it chosen?

For each of the 96 meshes of ``../shared/data/meshes_shrec07``, ``torchsym.detect(mesh)``
runs with the shipped config while step 9's hypotheses are recorded; each hypothesis's map
is then scored against the landmarks (landmark protocol of ``bench_mesh_shrec07.py``,
surface geodesics): its map after step 9's ZoomOut (``refined``, in ``refine.n_eigen``
eigenfunctions) and its map before (``raw``, the hypothesis's nearest rows). Beside each:
the tests step 9 reads (functional defects, geodesic distortion, reversed share, near-self
share) and the involution share (how many of the probe's vertices ``T(T(x))`` brings back
within the correspondence tolerance of ``x``).

A mesh is *right* when the returned map is above 75 %; else *missed by the choice* when some
hypothesis's map is above 75 %, else *never generated*. The first 5 meshes of each class
(by number) are the dev set, the other 7 the validation set.

    PYTHONPATH=. OMP_NUM_THREADS=1 python benchmarks/oracle_mesh_shrec07.py [--only ant,bust] [--tag TEXT]

Writes ``benchmarks/results/mesh_shrec07_oracle.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from collections import defaultdict
from pathlib import Path

import numpy as np
import torch

import torchsym
from torchsym.geometry.mesh import Mesh
from torchsym.io import read_mesh
from torchsym.mesh.intrinsic import solver
from torchsym.mesh import fmaps
from torchsym.mesh.intrinsic.coarsen import carry_map
from torchsym.mesh.intrinsic.hypotheses import first_image, sign_basis_image
from torchsym.mesh.intrinsic.refine import thesis_map
from torchsym.mesh.validate import validate_mesh
from torchsym.metrics.mesh import correspondence_rate

from bench_mesh_shrec07 import DATA, landmark_pairs, number, split_of  # noqa: E402 (benchmarks/ is on sys.path when run as a script)

HERE = Path(__file__).resolve().parent
RIGHT = 0.75


class Recorder:
    """Records step 9's workspace, hypotheses and table (and the coarse copy) of one solve."""

    def __init__(self):
        self.calls, self.copies = [], []
        self._choose, self._copy = solver.choose, solver.coarse_copy

    def __enter__(self):
        def choose(ws, candidates, images, seen):
            table, best = self._choose(ws, candidates, images, seen)
            self.calls.append((ws, list(candidates), table.copy(), best))
            return table, best

        def coarse_copy(*args, **kwargs):
            copy = self._copy(*args, **kwargs)
            self.copies.append(copy)
            return copy

        solver.choose, solver.coarse_copy = choose, coarse_copy
        return self

    def __exit__(self, *exc):
        solver.choose, solver.coarse_copy = self._choose, self._copy


def involution_share(ws, image_map: np.ndarray) -> float:
    """Share of the probe's ball vertices ``x`` with ``T(T(x))`` within the tolerance of ``x`` (``image_map``: ``(V,)``)."""
    probe = ws.probe
    x = ws.rows[probe.ball_rows]
    back = image_map[image_map[x]]
    return float(np.mean(probe.balls[np.arange(x.size), back] < probe.radius))


def extrinsic_residual(v: np.ndarray, rows: np.ndarray, image: np.ndarray) -> float:
    """RMS distance between ``v[image]`` and ``v[rows]`` moved by their best improper orthogonal map (a mirror
    and a rotation), over the RMS radius of ``v[rows]``: 0 for a map of an extrinsic reflection."""
    x, y = v[rows] - v[rows].mean(axis=0), v[image] - v[image].mean(axis=0)
    u, _, vt = np.linalg.svd(x.T @ y)
    d = np.ones(3)
    d[2] = -1.0 if np.linalg.det(u @ vt) > 0 else 1.0  # det of the orthogonal map: -1
    q = u @ np.diag(d) @ vt  # x @ q ~ y
    return float(np.sqrt(np.mean(np.sum((x @ q - y) ** 2, axis=1)) / np.mean(np.sum(x**2, axis=1))))


def score_candidates(mesh, entry: dict, rec: Recorder) -> tuple[list[dict], float]:
    """Each hypothesis's row (rates, tests) and step 9's limit on the distortion."""
    ws, candidates, table, best = rec.calls[-1]
    pairs = landmark_pairs(entry)
    checked = validate_mesh(mesh, components="largest", min_vertices=14)
    comp_v = checked.mesh.vertices.double().numpy()

    inner = None
    if rec.copies:  # the copy's own largest component was solved
        copy = rec.copies[-1]
        inner = validate_mesh(Mesh(torch.from_numpy(copy.vertices), torch.from_numpy(copy.faces)), components="largest", min_vertices=14)

    def to_input(solved_map: np.ndarray) -> np.ndarray:
        full = solved_map
        if inner is not None:
            full = carry_map(rec.copies[-1], comp_v, inner.map_to_input(torch.from_numpy(solved_map)).numpy())
        return checked.map_to_input(torch.from_numpy(full)).numpy()

    def rate(solved_map: np.ndarray) -> float:
        return float(correspondence_rate(mesh, to_input(solved_map), landmarks=pairs).rate)

    out = []
    for i, cand in enumerate(candidates):
        row = {"index": i, "name": cand.name, "chosen": i == best, "usable": bool(cand.usable), "screened": cand.refined is None,
               "tests": [float(x) for x in table[i]], "refined_rate": None, "raw_rate": None}
        if cand.usable:
            raw, _ = thesis_map(cand, 0.0)
            row["raw_rate"] = rate(raw)
        fitted = cand.refined
        if fitted is None and cand.usable:  # screened out by step 9: refined here all the same
            start = sign_basis_image(ws, cand) if cand.name == "signs" else first_image(ws, cand)
            image, fitted = fmaps.zoomout(ws.big, ws.area, ws.rows, start, ws.plan.ks, ws.search, ws.settings.refine.involution)
            row["start_near_self"] = ws.probe.near_self(start)
        if fitted is not None:
            full = ws.search.map_every_vertex(fitted)
            row["refined_rate"] = rate(full)
            row["reversed"] = ws.reversed_share(full) if ws.orient is not None else None
            row["involution"] = involution_share(ws, full)
            row["near_self"] = ws.probe.near_self(full[ws.rows])
            row["distortion"] = ws.probe.distortion(full[ws.rows])
            row["extrinsic"] = extrinsic_residual(ws.v, ws.rows, full[ws.rows])
        out.append(row)
    return out, ws.limit


def verdict(final: float, cands: list[dict]) -> str:
    best = max([c["refined_rate"] or 0.0 for c in cands] + [c["raw_rate"] or 0.0 for c in cands])
    if final > RIGHT:
        return "right"
    return "missed" if best > RIGHT else "never"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", default="", help="comma-separated classes")
    ap.add_argument("--tag", default="")
    ap.add_argument("--out", default="mesh_shrec07_oracle")
    ap.add_argument("--set", default="", help="JSON overrides of the shipped config (a variant's oracle)")
    args = ap.parse_args()
    torch.set_num_threads(int(os.environ.get("OMP_NUM_THREADS", "1")))
    index = json.loads((DATA / "landmarks.json").read_text())
    names = sorted(index, key=lambda n: (index[n]["class"], number(n)))
    if args.only:
        names = [n for n in names if index[n]["class"] in args.only.split(",")]
    over = json.loads(args.set) if args.set else {}
    load = os.getloadavg()
    rows = []
    for name in names:
        entry, mesh = index[name], read_mesh(DATA / name)
        with Recorder() as rec:
            tic = time.perf_counter()
            result = torchsym.detect(mesh, **over) if over else torchsym.detect(mesh)
            seconds = time.perf_counter() - tic
        final = float(correspondence_rate(mesh, result.map.numpy(), landmarks=landmark_pairs(entry)).rate)
        cands, limit = score_candidates(mesh, entry, rec)
        row = {"mesh": name, "class": entry["class"], "split": split_of(name, index), "vertices": mesh.num_vertices,
               "seconds": seconds, "final": final, "score": float(result.score), "hypothesis": result.hypothesis,
               "limit": limit, "candidates": cands, "verdict": verdict(final, cands)}
        rows.append(row)
        best = max([c["refined_rate"] or 0.0 for c in cands])
        print(f"{name:18s} {row['split']} final {final:.2f} best refined {best:.2f} {row['verdict']:6s} "
              + " ".join(f"{c['name'][:3]}:{'-' if c['refined_rate'] is None else round(c['refined_rate'], 2)}"
                         f"{'*' if c['chosen'] else ''}" for c in cands), flush=True)
    out = {"tag": args.tag, "load_before": load, "load_after": os.getloadavg(), "rows": rows}
    (HERE / "results" / f"{args.out}.json").write_text(json.dumps(out, indent=1))
    (HERE / "results" / f"{args.out}.md").write_text(report(out))
    print(report(out))


def report(out: dict) -> str:
    lines = [
        "# Step 9's oracle on SHREC'07 (96 meshes): right map generated and missed, or never generated",
        "",
        f"`python benchmarks/oracle_mesh_shrec07.py` {out['tag']}; `torchsym.detect`, shipped config; load "
        f"{out['load_before'][0]:.1f} before, {out['load_after'][0]:.1f} after. A hypothesis's map is right above "
        f"{100 * RIGHT:.0f} % of the landmarks (surface geodesics). *oracle*: the best of the hypotheses' maps (refined "
        "by step 9's ZoomOut, or raw). Dev: the first 5 of each class; val: the other 7.",
        "",
    ]
    for split in ("dev", "val"):
        mine = [r for r in out["rows"] if r["split"] == split]
        if not mine:
            continue
        lines += [f"## {split} ({len(mine)} meshes)", "",
                  "| class | meshes | rate % | oracle rate % | right | missed by the choice | never generated |",
                  "|---|---|---|---|---|---|---|"]
        by = defaultdict(list)
        for r in mine:
            by[r["class"]].append(r)
        for c in [*sorted(by), "all"]:
            rs = mine if c == "all" else by[c]
            oracle = [max([x["refined_rate"] or 0.0 for x in r["candidates"]] + [x["raw_rate"] or 0.0 for x in r["candidates"]])
                      for r in rs]
            count = lambda v: sum(r["verdict"] == v for r in rs)  # noqa: E731
            lines.append(f"| {c} | {len(rs)} | {100 * np.mean([r['final'] for r in rs]):.1f} | {100 * np.mean(oracle):.1f} | "
                         f"{count('right')} | {count('missed')} | {count('never')} |")
        lines.append("")
    lines += ["## Meshes not right", "", "| mesh | split | rate % | chosen | best hypothesis (refined %) |", "|---|---|---|---|---|"]
    for r in out["rows"]:
        if r["verdict"] == "right":
            continue
        best = max(r["candidates"], key=lambda x: max(x["refined_rate"] or 0.0, x["raw_rate"] or 0.0))
        lines.append(f"| {r['mesh']} | {r['split']} | {100 * r['final']:.0f} | {r['hypothesis']} | {best['name']} "
                     f"({100 * (best['refined_rate'] or 0):.0f}, raw {100 * (best['raw_rate'] or 0):.0f}) |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
