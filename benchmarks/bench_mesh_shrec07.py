"""Intrinsic symmetry on published meshes: SHREC'07 watertight, landmark protocol (thesis Sec. 6.3.2).

The 96 meshes of ``../shared/data/meshes_shrec07`` (8 classes x 12, 3.2k-53k vertices, as
released) with their annotated symmetric landmark pairs (Kim et al. 2010). A landmark's
predicted mirror is correct within geodesic ``sqrt(area / 20 pi)`` of its annotated partner,
both directions of every pair (a pair ``[i, i]`` once); the mesh rate is the share of
meshes above 75 %. Geodesics on the surface (edge paths straightened by FlipOut, exact
polyhedral geodesics) and along edges alone (stricter) side by side. The first 5 meshes of
each class (by number) are the dev set the method was chosen on, the other 7 the
validation set; every figure is given for each apart.

Runs, in one process: ``torchsym.detect(mesh)`` with the shipped config
(``configs/mesh_intrinsic.yaml``), and pyFM's orientation-reversing functional self-map as
the peer (``bench_mesh.pyfm_map``). Reports per class, median seconds per mesh and per step
(the result's ``timings``, with the machine's load), and the ROC AUC of the result's
``score`` for telling right maps (rate above 75 %) from wrong ones. ``--variant NAME=JSON``
runs the solver with settings under choice (rows to ``results/mesh_shrec07_NAME.json``);
``--loco A,B`` then adds the leave-one-class-out row on the dev set. ``--timing JSON``: wall and
processor seconds of ``detect`` against it with these overrides, interleaved, one mesh in three.

    PYTHONPATH=. python benchmarks/bench_mesh_shrec07.py [--no-pyfm] [--threads 1] [--loco A,B] [--report-only] [--tag TEXT]
    PYTHONPATH=. python benchmarks/bench_mesh_shrec07.py --variant NAME='{"hypotheses.sign_basis": 0}'
    PYTHONPATH=. python benchmarks/bench_mesh_shrec07.py --timing '{"hypotheses.sign_basis": 0}'

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
import torch

import torchsym
from torchsym.io import read_mesh
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


def number(name: str) -> int:
    return int(name.rsplit("_", 1)[1].split(".")[0])


def split_of(name: str, index: dict) -> str:
    """``"dev"`` for the first 5 meshes of a class (by number), else ``"val"``."""
    same = sorted((n for n in index if index[n]["class"] == index[name]["class"]), key=number)
    return "dev" if same.index(name) < 5 else "val"


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
            "mesh": name, "class": entry["class"], "split": split_of(name, index), "vertices": mesh.num_vertices,
            "seconds": seconds, "timings": result.timings,
            "surface": correspondence_rate(mesh, pred, landmarks=pairs).rate,
            "edges": correspondence_rate(mesh, pred, landmarks=pairs, geodesics="edges").rate,
            "score": result.score, "hypothesis": result.hypothesis, "load": os.getloadavg()[0],
        }
        if use_pyfm:
            p2p, t = pyfm_map(mesh)
            row["pyfm"] = correspondence_rate(mesh, p2p, landmarks=pairs).rate
            row["pyfm_seconds"] = t
        print(f"{name:20s} {row['split']} {row['vertices']:6d} {row['surface']:.3f} {row['edges']:.3f} score {row['score']:.2f} "
              f"{seconds:.2f}s {row['hypothesis']}" + (f" | pyFM {row['pyfm']:.3f} {t:.1f}s" if use_pyfm else ""), flush=True)
        rows.append(row)
    return rows


def summary(rows: list[dict], key: str = "surface") -> dict:
    by = defaultdict(list)
    for r in rows:
        by[r["class"]].append(r[key])
    rates = [r[key] for r in rows]
    return {
        "meshes": len(rows), "rate": float(np.mean(rates)), "mesh_rate": float(np.mean(np.array(rates) > 0.75)),
        "classes": {c: float(np.mean(v)) for c, v in sorted(by.items())},
    }


def split_summary(rows: list[dict]) -> dict:
    """Per split (``dev``, ``val``): rates on the surface and along edges, pyFM's, median seconds and the score's AUC."""
    out = {}
    for split in ("dev", "val"):
        mine = [r for r in rows if r["split"] == split]
        if not mine:
            continue
        out[split] = {
            "surface": summary(mine), "edges": summary(mine, "edges"),
            "median_seconds": statistics.median(r["seconds"] for r in mine),
            "score_auc": roc_auc([r["score"] for r in mine], [r["surface"] > 0.75 for r in mine]),
        }
        if all("pyfm" in r for r in mine):
            out[split]["pyfm"] = summary(mine, "pyfm")
            out[split]["pyfm_median_seconds"] = statistics.median(r["pyfm_seconds"] for r in mine)
    return out


def step_seconds(rows: list[dict]) -> dict[str, float]:
    """Median seconds of each step over the meshes (0 where a step did not run)."""
    steps = sorted({k for r in rows for k in r.get("timings", {})})
    return {k: statistics.median(r["timings"].get(k, 0.0) for r in rows) for k in steps}


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
    ap.add_argument("--no-pyfm", action="store_true", help="no pyFM in this run")
    ap.add_argument("--variant", default="", help='NAME=JSON: run intrinsic_symmetry with these overrides instead, '
                                                   'rows to results/mesh_shrec07_NAME.json')
    ap.add_argument("--loco", default="", help="comma-separated variant names whose rows (run before) enter the leave-one-class-out choice (dev set)")
    ap.add_argument("--only", default="", help="comma-separated classes, or dev / val")
    ap.add_argument("--report-only", action="store_true", help="rebuild the report from the rows of the last run (with --loco)")
    ap.add_argument("--timing", default="", metavar="JSON",
                    help="wall and processor seconds of detect against detect with these overrides, interleaved, "
                         "every third mesh (results/mesh_shrec07_timing.md)")
    ap.add_argument("--threads", type=int, default=0, help="torch's threads (0: as it is)")
    ap.add_argument("--tag", default="")
    args = ap.parse_args()
    if args.threads:
        torch.set_num_threads(args.threads)
    index = json.loads((DATA / "landmarks.json").read_text())
    names = sorted(index, key=lambda n: (index[n]["class"], number(n)))
    if args.only:
        keep = set(args.only.split(","))
        names = [n for n in names if index[n]["class"] in keep or split_of(n, index) in keep]
    load = os.getloadavg()
    if args.timing:
        timing(index, names[::3], json.loads(args.timing), args.tag)
        return
    if args.variant:
        vname, over = args.variant.split("=", 1)
        over = json.loads(over)
        rows = run(names, index, lambda m: torchsym.detect(m, **over), False)
        out = {"overrides": over, "rows": rows, "load_before": load, "load_after": os.getloadavg(), "splits": split_summary(rows)}
        (HERE / "results" / f"mesh_shrec07_{vname}.json").write_text(json.dumps(out, indent=1))
        print(vname, json.dumps({k: {"rate": v["surface"]["rate"], "mesh_rate": v["surface"]["mesh_rate"], "auc": v["score_auc"],
                                     "classes": v["surface"]["classes"]} for k, v in out["splits"].items()}))
        return
    if args.report_only:
        last = json.loads((HERE / "results" / "mesh_shrec07.json").read_text())
        rows, args.tag, load, load_after = last["rows"], last["tag"], last["load_before"], last["load_after"]
    else:
        rows = run(names, index, torchsym.detect, not args.no_pyfm)
        load_after = os.getloadavg()
    out = {
        "tag": args.tag, "threads": torch.get_num_threads(), "load_before": load, "load_after": load_after,
        "load_during": [min(r["load"] for r in rows), max(r["load"] for r in rows)], "rows": rows,
        "splits": split_summary(rows), "median_seconds": statistics.median(r["seconds"] for r in rows),
        "step_seconds": step_seconds(rows),
    }
    if args.loco:
        dev = lambda rs: [r for r in rs if r.get("split", split_of(r["mesh"], index)) == "dev"]  # noqa: E731
        variant_rows = {"shipped": dev(rows)}
        for vname in args.loco.split(","):
            path = HERE / "results" / f"mesh_shrec07_{vname}.json"
            if path.exists():
                variant_rows[vname] = dev(json.loads(path.read_text())["rows"])
            else:
                print(f"no rows of variant {vname}: left out of the choice", flush=True)
        out["variants"] = {v: summary(r) for v, r in variant_rows.items()}
        out["loco"] = leave_one_class_out(variant_rows)
    (HERE / "results" / "mesh_shrec07.json").write_text(json.dumps(out, indent=1))
    (HERE / "results" / "mesh_shrec07.md").write_text(report(out))
    print(report(out))


def timing(index: dict, names: list[str], over: dict, tag: str) -> None:
    """A/B of the shipped config against it with ``over``, interleaved per mesh (the order alternating)."""
    runs = {"shipped": lambda m: torchsym.detect(m), f"with {json.dumps(over)}": lambda m: torchsym.detect(m, **over)}
    rows = []
    for i, name in enumerate(names):
        mesh = read_mesh(DATA / name)
        for label in list(runs)[:: 1 if i % 2 == 0 else -1]:
            wall, cpu = time.perf_counter(), time.process_time()
            runs[label](mesh)
            rows.append({"mesh": name, "run": label, "vertices": mesh.num_vertices, "wall": time.perf_counter() - wall,
                         "cpu": time.process_time() - cpu, "load": os.getloadavg()[0]})
            print(rows[-1], flush=True)
    lines = [f"# Seconds per mesh on SHREC'07, shipped config against {json.dumps(over)} (interleaved)", "",
             f"`python benchmarks/bench_mesh_shrec07.py --timing '{json.dumps(over)}'` {tag}: every third of the 96 meshes, "
             f"{torch.get_num_threads()} torch threads; processor seconds count every thread of the solver.", "",
             "| run | meshes | median wall s | median processor s | load during |", "|---|---|---|---|---|"]
    for label in runs:
        mine = [r for r in rows if r["run"] == label]
        lines.append(f"| {label} | {len(mine)} | {statistics.median(r['wall'] for r in mine):.2f} | "
                     f"{statistics.median(r['cpu'] for r in mine):.2f} | "
                     f"{min(r['load'] for r in mine):.1f}-{max(r['load'] for r in mine):.1f} |")
    (HERE / "results" / "mesh_shrec07_timing.json").write_text(json.dumps(rows, indent=1))
    (HERE / "results" / "mesh_shrec07_timing.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def report(out: dict) -> str:
    pct = lambda x: f"{100 * x:.1f}"  # noqa: E731
    lines = [
        "# Intrinsic symmetry on SHREC'07 watertight meshes as released (landmark protocol)",
        "",
        f"`python benchmarks/bench_mesh_shrec07.py` {out['tag']}; {out['threads']} torch threads; load average "
        f"{out['load_before'][0]:.1f} before, {out['load_during'][0]:.1f}-{out['load_during'][1]:.1f} during, "
        f"{out['load_after'][0]:.1f} after (2 shared cores). `torchsym.detect(mesh)`, shipped config; pyFM in the same run. "
        "Dev: the first 5 meshes of each class (the method was chosen on them); val: the other 7.",
        "",
    ]
    for split, s in out["splits"].items():
        classes = list(s["surface"]["classes"])
        lines += [
            f"## {split} ({s['surface']['meshes']} meshes)", "",
            "| method | geodesics | rate % | mesh rate % | " + " | ".join(classes) + " |",
            "|---|---|---|---|" + "---|" * len(classes),
        ]
        rows = [("torchsym", "surface", s["surface"]), ("torchsym", "edges", s["edges"])]
        if "pyfm" in s:
            rows.append(("pyFM", "surface", s["pyfm"]))
        for method, geo, t in rows:
            lines.append(f"| {method} | {geo} | {pct(t['rate'])} | {pct(t['mesh_rate'])} | "
                         + " | ".join(pct(t["classes"][c]) for c in classes) + " |")
        lines += [
            "",
            f"Median seconds per mesh: torchsym {s['median_seconds']:.2f}"
            + (f", pyFM {s['pyfm_median_seconds']:.2f}" if "pyfm_median_seconds" in s else "") + ". "
            f"ROC AUC of `result.score` (right map: rate above 75 %): {s['score_auc']:.3f}.",
            "",
        ]
    if "loco" in out:
        lines += ["## Variants on the dev set", "", "| variant | rate % | mesh rate % |", "|---|---|---|"]
        for variant, t in out["variants"].items():
            lines.append(f"| {variant} (in-sample) | {pct(t['rate'])} | {pct(t['mesh_rate'])} |")
        lines += [f"| leave-one-class-out choice | {pct(out['loco']['rate'])} | {pct(out['loco']['mesh_rate'])} |", "",
                  f"Leave-one-class-out picks: {out['loco']['picks']}.", ""]
    lines += [f"## Seconds per step (median over the {len(out['rows'])} meshes; all meshes {out['median_seconds']:.2f} s)", "",
              "Each step's own stopwatch (`result.timings`); branches on threads count their own time.", "",
              "| " + " | ".join(out["step_seconds"]) + " |", "|" + "---|" * len(out["step_seconds"]),
              "| " + " | ".join(f"{v:.3f}" for v in out["step_seconds"].values()) + " |", ""]
    lines += ["## Meshes", "", "| mesh | split | vertices | rate % | edges % | score | hypothesis | s | pyFM % |",
              "|---|---|---|---|---|---|---|---|---|"]
    for r in out["rows"]:
        lines.append(f"| {r['mesh']} | {r['split']} | {r['vertices']} | {pct(r['surface'])} | {pct(r['edges'])} | {r['score']:.2f} | "
                     f"{r['hypothesis']} | {r['seconds']:.2f} | {pct(r['pyfm']) if 'pyfm' in r else ''} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
