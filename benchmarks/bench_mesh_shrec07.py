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
    PYTHONPATH=. python benchmarks/bench_mesh_shrec07.py --pyfm-only 5
    PYTHONPATH=. python benchmarks/bench_mesh_shrec07.py [--no-pyfm] [--loco A,B] [--report-only] [--tag TEXT]

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
    ap.add_argument("--no-pyfm", action="store_true", help="no pyFM in this run (rows of --pyfm-only are used when present)")
    ap.add_argument("--variant", default="", help='NAME=JSON: run intrinsic_symmetry with these overrides instead, '
                                                   'rows to results/mesh_shrec07_NAME.json')
    ap.add_argument("--loco", default="", help="comma-separated variant names whose rows (run before) enter the leave-one-class-out choice")
    ap.add_argument("--pyfm-only", type=int, default=0, metavar="STEP",
                    help="run only pyFM, on every STEP-th mesh of each class, rows to results/mesh_shrec07_pyfm.json")
    ap.add_argument("--report-only", action="store_true", help="rebuild the report from the rows of the last run (with --loco)")
    ap.add_argument("--timing", action="store_true",
                    help="wall and processor seconds of detect against sign_basis 0, interleaved, one mesh per class "
                         "(results/mesh_shrec07_timing.md)")
    ap.add_argument("--tag", default="")
    args = ap.parse_args()
    index = json.loads((DATA / "landmarks.json").read_text())
    names = sorted(index, key=lambda n: (index[n]["class"], n))
    load = os.getloadavg()
    if args.timing:
        timing(index, names)
        return
    if args.pyfm_only:
        rows = []
        for name in names:
            if int(name.rsplit("_", 1)[1].split(".")[0]) % 5 % args.pyfm_only:
                continue
            mesh = read_mesh(DATA / name)
            p2p, t = pyfm_map(mesh)
            rows.append({"mesh": name, "class": index[name]["class"], "pyfm": correspondence_rate(mesh, p2p, landmarks=landmark_pairs(index[name])).rate,
                         "pyfm_seconds": t})
            print(rows[-1], flush=True)
        out = {"rows": rows, "load_before": load, "load_after": os.getloadavg()}
        (HERE / "results" / "mesh_shrec07_pyfm.json").write_text(json.dumps(out, indent=1))
        return
    if args.variant:
        vname, over = args.variant.split("=", 1)
        over = json.loads(over)
        rows = run(names, index, lambda m: intrinsic_symmetry(m, None, **over), False)
        out = {"overrides": over, "rows": rows, "load_before": load, "load_after": os.getloadavg(), **summary(rows)}
        (HERE / "results" / f"mesh_shrec07_{vname}.json").write_text(json.dumps(out, indent=1))
        print(vname, {k: out[k] for k in ("rate", "mesh_rate", "classes")})
        return
    if args.report_only:
        last = json.loads((HERE / "results" / "mesh_shrec07.json").read_text())
        rows, args.tag, load, load_after = last["rows"], last["tag"], last["load_before"], last["load_after"]
    else:
        rows = run(names, index, torchsym.detect, not args.no_pyfm)
        load_after = os.getloadavg()
    out = {
        "tag": args.tag, "load_before": load, "load_after": load_after, "rows": rows,
        "surface": summary(rows), "edges": summary(rows, "edges"),
        "median_seconds": statistics.median(r["seconds"] for r in rows),
        "score_auc": roc_auc([r["score"] for r in rows], [r["surface"] > 0.75 for r in rows]),
    }
    peer = HERE / "results" / "mesh_shrec07_pyfm.json"
    if args.no_pyfm and peer.exists():  # pyFM run apart, on some of the meshes
        pyfm_rows = json.loads(peer.read_text())["rows"]
        same = {r["mesh"]: r for r in rows}
        out["pyfm"] = summary(pyfm_rows, "pyfm")
        out["pyfm_meshes"] = len(pyfm_rows)
        out["torchsym_on_pyfm_meshes"] = summary([same[r["mesh"]] for r in pyfm_rows])
        out["pyfm_median_seconds"] = statistics.median(r["pyfm_seconds"] for r in pyfm_rows)
    elif not args.no_pyfm:
        out["pyfm"] = summary(rows, "pyfm")
        out["pyfm_median_seconds"] = statistics.median(r["pyfm_seconds"] for r in rows)
    if args.loco:
        variant_rows = {"shipped": rows}
        for vname in args.loco.split(","):
            path = HERE / "results" / f"mesh_shrec07_{vname}.json"
            if path.exists():
                variant_rows[vname] = json.loads(path.read_text())["rows"]
            else:
                print(f"no rows of variant {vname}: left out of the choice", flush=True)
        out["variants"] = {v: summary(r) for v, r in variant_rows.items()}
        out["loco"] = leave_one_class_out(variant_rows)
    (HERE / "results" / "mesh_shrec07.json").write_text(json.dumps(out, indent=1))
    (HERE / "results" / "mesh_shrec07.md").write_text(report(out))
    print(report(out))


def timing(index: dict, names: list[str]) -> None:
    """A/B of the shipped config against it without the sign hypotheses, interleaved per mesh."""
    runs = {"shipped": lambda m: torchsym.detect(m), "sign_basis 0": lambda m: intrinsic_symmetry(m, None, **{"hypotheses.sign_basis": 0})}
    rows = []
    for name in names[4::5]:  # one mesh per class
        mesh = read_mesh(DATA / name)
        for label, solve in runs.items():
            wall, cpu = time.perf_counter(), time.process_time()
            solve(mesh)
            rows.append({"mesh": name, "run": label, "wall": time.perf_counter() - wall, "cpu": time.process_time() - cpu,
                         "load": os.getloadavg()[0]})
            print(rows[-1], flush=True)
    lines = ["# Seconds per mesh on SHREC'07, shipped config against sign_basis 0 (interleaved)", "",
             "`python benchmarks/bench_mesh_shrec07.py --timing`; processor seconds count every thread of the solver.", "",
             "| run | median wall s | median processor s | load during |", "|---|---|---|---|"]
    for label in runs:
        mine = [r for r in rows if r["run"] == label]
        lines.append(f"| {label} | {statistics.median(r['wall'] for r in mine):.2f} | {statistics.median(r['cpu'] for r in mine):.2f} | "
                     f"{min(r['load'] for r in mine):.1f}-{max(r['load'] for r in mine):.1f} |")
    (HERE / "results" / "mesh_shrec07_timing.json").write_text(json.dumps(rows, indent=1))
    (HERE / "results" / "mesh_shrec07_timing.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


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
        subset = f" ({out['pyfm_meshes']} meshes)" if "pyfm_meshes" in out else ""
        rows.append((f"pyFM{subset}", "surface", out["pyfm"]))
        if "torchsym_on_pyfm_meshes" in out:
            rows.append((f"torchsym on the same{subset}", "surface", out["torchsym_on_pyfm_meshes"]))
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
