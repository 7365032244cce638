"""Intrinsic symmetry on published meshes: SHREC'07 watertight, landmark protocol (thesis Sec. 6.3.2).

The 40 meshes of ``../shared/data/meshes_shrec07`` (8 classes, 3.2k-28k vertices, as
released) with their annotated symmetric landmark pairs (Kim et al. 2010). A landmark's
predicted mirror is correct within geodesic ``sqrt(area / 20 pi)`` of its annotated partner,
both directions of every pair (a pair ``[i, i]`` once); the mesh rate is the share of
meshes above 75 %. Geodesics on the surface (edge paths straightened by FlipOut, exact
polyhedral geodesics) and along edges alone (stricter) side by side.

Runs, in one process: ``torchsym.detect(mesh)`` with the shipped config
(``configs/mesh_intrinsic.yaml``), and pyFM's orientation-reversing functional self-map as
the peer (``bench_mesh.pyfm_map``). Reports per class, median seconds per mesh (with the
machine's load), and the ROC AUC of the result's ``score`` for telling right maps (rate
above 75 %) from wrong ones. ``--variant NAME=JSON`` runs the solver with settings under
choice (rows to ``results/mesh_shrec07_NAME.json``); ``--loco A,B`` then adds the
leave-one-class-out row: each class scored with the variant (shipped, A, B) that does best
on the other seven.

    PYTHONPATH=. python benchmarks/bench_mesh_shrec07.py --variant NAME='{"hypotheses.sign_basis": 0}'
    PYTHONPATH=. python benchmarks/bench_mesh_shrec07.py [--no-pyfm] [--loco A,B] [--tag TEXT]

Writes ``benchmarks/results/mesh_shrec07.md`` and ``.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

import torchsym
from torchsym.io import read_mesh
from torchsym.mesh import intrinsic_symmetry
from torchsym.metrics.mesh import correspondence_rate

from bench_mesh import pyfm_map  # noqa: E402 (benchmarks/ is on sys.path when run as a script)

HERE = Path(__file__).resolve().parent
DATA = HERE.parent.parent / "shared" / "data" / "meshes_shrec07"


def landmark_pairs(entry: dict) -> np.ndarray:
    """``(L, 2)`` directed pairs (landmark vertex, its annotated mirror), both directions, each once."""
    lm = np.asarray(entry["landmarks"], dtype=np.int64)
    pairs = {(int(lm[i]), int(lm[j])) for i, j in entry["sym_pairs"]} | {(int(lm[j]), int(lm[i])) for i, j in entry["sym_pairs"]}
    return np.array(sorted(pairs), dtype=np.int64)


def roc_auc(scores: list[float], positive: list[bool]) -> float:
    """Area under the ROC curve (ties count half); nan without both classes."""
    s, y = np.asarray(scores, float), np.asarray(positive, bool)
    pos, neg = s[y], s[~y]
    if not pos.size or not neg.size:
        return float("nan")
    return float(((pos[:, None] > neg[None, :]).sum() + 0.5 * (pos[:, None] == neg[None, :]).sum()) / (pos.size * neg.size))


def run(names: list[str], index: dict, solve, use_pyfm: bool) -> list[dict]:
    rows = []
    for name in names:
        entry, mesh = index[name], read_mesh(DATA / name)
        pairs = landmark_pairs(entry)
        tic = time.perf_counter()
        result = solve(mesh)
        seconds = time.perf_counter() - tic
        pred = result.map.numpy()
        row = {
            "mesh": name, "class": entry["class"], "vertices": mesh.num_vertices, "seconds": seconds,
            "surface": correspondence_rate(mesh, pred, landmarks=pairs).rate,
            "edges": correspondence_rate(mesh, pred, landmarks=pairs, geodesics="edges").rate,
            "score": result.score, "hypothesis": result.hypothesis,
        }
        if use_pyfm:
            p2p, t = pyfm_map(mesh)
            row["pyfm"] = correspondence_rate(mesh, p2p, landmarks=pairs).rate
            row["pyfm_seconds"] = t
        print(f"{name:20s} {row['vertices']:6d} {row['surface']:.3f} {row['edges']:.3f} score {row['score']:.2f} "
              f"{seconds:.2f}s {row['hypothesis']}" + (f" | pyFM {row['pyfm']:.3f}" if use_pyfm else ""), flush=True)
        rows.append(row)
    return rows


def summary(rows: list[dict], key: str = "surface") -> dict:
    by = defaultdict(list)
    for r in rows:
        by[r["class"]].append(r[key])
    rates = [r[key] for r in rows]
    return {
        "rate": float(np.mean(rates)), "mesh_rate": float(np.mean(np.array(rates) > 0.75)),
        "classes": {c: float(np.mean(v)) for c, v in by.items()},
    }


def leave_one_class_out(variant_rows: dict[str, list[dict]]) -> dict:
    """Each class scored with the variant of the best mean rate on the other classes."""
    classes = sorted({r["class"] for rows in variant_rows.values() for r in rows})
    held, picks = [], {}
    for c in classes:
        train = {v: np.mean([r["surface"] for r in rows if r["class"] != c]) for v, rows in variant_rows.items()}
        best = max(train, key=train.get)
        picks[c] = best
        held.extend(r for r in variant_rows[best] if r["class"] == c)
    return {"picks": picks, **summary(held)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--no-pyfm", action="store_true")
    ap.add_argument("--variant", default="", help='NAME=JSON: run intrinsic_symmetry with these overrides instead, '
                                                   'rows to results/mesh_shrec07_NAME.json')
    ap.add_argument("--loco", default="", help="comma-separated variant names whose rows (run before) enter the leave-one-class-out choice")
    ap.add_argument("--tag", default="")
    args = ap.parse_args()
    index = json.loads((DATA / "landmarks.json").read_text())
    names = sorted(index, key=lambda n: (index[n]["class"], n))
    load = os.getloadavg()
    if args.variant:
        vname, over = args.variant.split("=", 1)
        over = json.loads(over)
        rows = run(names, index, lambda m: intrinsic_symmetry(m, None, **over), False)
        out = {"overrides": over, "rows": rows, "load_before": load, "load_after": os.getloadavg(), **summary(rows)}
        (HERE / "results" / f"mesh_shrec07_{vname}.json").write_text(json.dumps(out, indent=1))
        print(vname, {k: out[k] for k in ("rate", "mesh_rate", "classes")})
        return
    rows = run(names, index, torchsym.detect, not args.no_pyfm)
    out = {
        "tag": args.tag, "load_before": load, "load_after": os.getloadavg(), "rows": rows,
        "surface": summary(rows), "edges": summary(rows, "edges"),
        "median_seconds": statistics.median(r["seconds"] for r in rows),
        "score_auc": roc_auc([r["score"] for r in rows], [r["surface"] > 0.75 for r in rows]),
    }
    if not args.no_pyfm:
        out["pyfm"] = summary(rows, "pyfm")
        out["pyfm_median_seconds"] = statistics.median(r["pyfm_seconds"] for r in rows)
    if args.loco:
        variant_rows = {"shipped": rows}
        for vname in args.loco.split(","):
            variant_rows[vname] = json.loads((HERE / "results" / f"mesh_shrec07_{vname}.json").read_text())["rows"]
        out["variants"] = {v: summary(r) for v, r in variant_rows.items()}
        out["loco"] = leave_one_class_out(variant_rows)
    (HERE / "results" / "mesh_shrec07.json").write_text(json.dumps(out, indent=1))
    (HERE / "results" / "mesh_shrec07.md").write_text(report(out))
    print(report(out))


def report(out: dict) -> str:
    classes = list(out["surface"]["classes"])
    pct = lambda x: f"{100 * x:.1f}"  # noqa: E731
    lines = [
        "# Intrinsic symmetry on SHREC'07 watertight meshes as released (landmark protocol)",
        "",
        f"`python benchmarks/bench_mesh_shrec07.py` {out['tag']}; load average {out['load_before'][0]:.1f} before, "
        f"{out['load_after'][0]:.1f} after (2 shared cores). `torchsym.detect(mesh)`, shipped config.",
        "",
        "| method | geodesics | rate % | mesh rate % | " + " | ".join(classes) + " |",
        "|---|---|---|---|" + "---|" * len(classes),
    ]
    rows = [("torchsym", "surface", out["surface"]), ("torchsym", "edges", out["edges"])]
    if "pyfm" in out:
        rows.append(("pyFM", "surface", out["pyfm"]))
    for variant, s in out.get("variants", {}).items():
        if variant != "shipped":
            rows.append((f"variant {variant} (in-sample)", "surface", s))
    if "loco" in out:
        rows.append(("leave-one-class-out choice", "surface", out["loco"]))
    for method, geo, s in rows:
        lines.append(f"| {method} | {geo} | {pct(s['rate'])} | {pct(s['mesh_rate'])} | "
                     + " | ".join(pct(s["classes"][c]) for c in classes) + " |")
    lines += [
        "",
        f"Median seconds per mesh: torchsym {out['median_seconds']:.2f}"
        + (f", pyFM {out['pyfm_median_seconds']:.2f}" if "pyfm_median_seconds" in out else "") + ".",
        f"ROC AUC of `result.score` (right map: rate above 75 %): {out['score_auc']:.3f}.",
    ]
    if "loco" in out:
        lines.append(f"Leave-one-class-out picks: {out['loco']['picks']}.")
    lines += ["", "| mesh | vertices | rate % | edges % | score | hypothesis | s |", "|---|---|---|---|---|---|---|"]
    for r in out["rows"]:
        lines.append(f"| {r['mesh']} | {r['vertices']} | {pct(r['surface'])} | {pct(r['edges'])} | {r['score']:.2f} | "
                     f"{r['hypothesis']} | {r['seconds']:.2f} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
