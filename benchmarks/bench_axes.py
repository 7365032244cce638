"""Benchmark of the axis stage on photographs, with imgsym 0.1.0 in the same run (thesis Sec. 2.4).

What a user runs: ``torchsym.detect(path)`` (the default pipeline for photos, the axis
stage, no overrides) on each photograph at its own size; beside it the previous default
(``configs/image_boundary_cliques.yaml``) and the peer ``imgsym`` (``detect_axes`` with
``nxc``, Cicconet et al. 2017, and ``xfeatures``, Loy & Eklundh 2006; its defaults, BGR
input), on the same photographs in the same run.

Sets: the 32 ICCV'17 dev photographs (validation only) and the ``check`` half of the Leeds
butterflies whose mask has an axis (``benchmarks/axes_data.py``; the ``choose`` half fitted
the decision's weights and is not scored here). ``nxc`` takes ~9 s a photograph: it runs on
the dev photographs and the first ``--nxc-butterflies`` check butterflies by name; the row
"butterflies (nxc subset)" scores every method on exactly those.

Figures: max F of one threshold swept over all photographs of a set (pooled), under the
thesis's criterion (3 deg, 0.025 min(w, h)) and the challenge's (10 deg, 20 % of GT
length); on the dev photographs also cross-validated: 4 folds (seed 2017), the threshold
of best F on three folds applied to the fourth, the held-out detections pooled; the top
axis right (challenge); axes returned per photograph; for the axis stage the share of
photographs with exactly one accepted axis and the F of the accepted axes; median seconds
(with the machine's load). Writes ``benchmarks/results/axes.md`` and ``axes.json``.

    PYTHONPATH=. python benchmarks/bench_axes.py [--nxc-butterflies 10]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import torch

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path[:0] = [str(ROOT), str(HERE)]

import axes_data  # noqa: E402

import torchsym  # noqa: E402
from torchsym.metrics.axes import evaluate_axes, match_axes  # noqa: E402

CRITERIA = ("thesis", "challenge")
N_FOLDS, FOLD_SEED = 4, 2017
METHODS = ("torchsym.detect (axis stage)", "boundary_cliques (before)", "imgsym xfeatures", "imgsym nxc")


def source_version() -> str:
    """A hash of the sources a detection depends on, so cached detections follow code changes."""
    h = hashlib.sha1()
    for sub in ("torchsym/image", "torchsym/features", "configs"):
        for p in sorted((ROOT / sub).rglob("*")):
            if p.suffix in (".py", ".yaml") and "symmetry_map" not in p.parts and "symmslic" not in p.parts:
                h.update(p.read_bytes())
    return h.hexdigest()[:12]


def imgsym_axes(path: Path, detector: str) -> tuple[list, list]:
    """imgsym's axes of a photograph as segments ``x1, y1, x2, y2`` and its strengths."""
    import cv2
    import imgsym

    angles, mids, lengths, strengths = imgsym.detect_axes(cv2.imread(str(path)), detector=detector)
    segs = []
    for a, m, s in zip(angles, mids, lengths):
        d = np.array([np.cos(a), -np.sin(a)]) * s / 2  # imgsym's drawing convention (y down)
        segs.append([*(np.asarray(m) + d), *(np.asarray(m) - d)])
    return [[float(v) for v in s] for s in segs], [float(v) for v in strengths]


def detect(method: str, path: Path, cache: Path, version: str) -> dict:
    """``{"axes", "scores", "accepted", "size", "seconds"}`` of one detection, cached."""
    key = hashlib.sha1(json.dumps([method, str(path), version]).encode()).hexdigest()
    file = cache / f"{key}.json"
    if file.exists():
        return json.loads(file.read_text())
    import cv2

    size = list(cv2.imread(str(path)).shape[:2])
    t0 = time.perf_counter()
    if method.startswith("imgsym"):
        axes, scores = imgsym_axes(path, method.split()[1])
        accepted = [True] * len(axes)
    else:
        cfg = None if method.startswith("torchsym") else ROOT / "configs/image_boundary_cliques.yaml"
        res = torchsym.detect(str(path), cfg) if cfg else torchsym.detect(str(path))
        axes, scores, accepted = res.axes.tolist(), res.scores.tolist(), res.accepted.tolist()
    out = {"axes": axes, "scores": scores, "accepted": accepted, "size": size, "seconds": time.perf_counter() - t0}
    file.write_text(json.dumps(out))
    return out


def _hits(run: dict, gt: torch.Tensor, criterion: str) -> tuple[np.ndarray, np.ndarray]:
    a = torch.tensor(run["axes"], dtype=torch.float64).reshape(-1, 4)
    s = torch.tensor(run["scores"], dtype=torch.float64)
    ok = match_axes(a, gt, image_size=tuple(run["size"]), scores=s, criterion=criterion) if len(s) else torch.zeros(0, dtype=torch.bool)
    return s.numpy(), ok.numpy()


def max_f(runs: dict, gts: dict, names: list[str], criterion: str) -> float:
    dets = [(torch.tensor(runs[n]["axes"]).reshape(-1, 4), torch.tensor(runs[n]["scores"])) for n in names]
    return evaluate_axes(dets, [gts[n] for n in names], [tuple(runs[n]["size"]) for n in names], criterion=criterion).max_f


def counts_at(runs: dict, gts: dict, names: list[str], criterion: str, thr: float) -> tuple[int, int, int]:
    tp = fp = fn = 0
    for n in names:
        s, ok = _hits(runs[n], gts[n], criterion)
        keep = s >= thr
        t = int(ok[keep].sum())
        tp, fp, fn = tp + t, fp + int(keep.sum()) - t, fn + int(gts[n].shape[0]) - t
    return tp, fp, fn


def f_of(tp: int, fp: int, fn: int) -> float:
    return 2 * tp / max(2 * tp + fp + fn, 1)


def best_threshold(runs: dict, gts: dict, names: list[str], criterion: str) -> float:
    scores = sorted({s for n in names for s in runs[n]["scores"]})
    if not scores:
        return float("inf")
    return max(scores, key=lambda t: f_of(*counts_at(runs, gts, names, criterion, t)))


def folds(names: list[str]) -> list[list[str]]:
    order = np.random.default_rng(FOLD_SEED).permutation(len(names))
    ranked = [sorted(names)[i] for i in order]
    return [sorted(ranked[k::N_FOLDS]) for k in range(N_FOLDS)]


def cross_validated(runs: dict, gts: dict, names: list[str], criterion: str) -> float:
    """F of the held-out detections pooled, each fold at the threshold best on the other folds."""
    tp = fp = fn = 0
    split = folds(names)
    for k, held in enumerate(split):
        train = [n for j, f in enumerate(split) if j != k for n in f]
        c = counts_at(runs, gts, held, criterion, best_threshold(runs, gts, train, criterion))
        tp, fp, fn = tp + c[0], fp + c[1], fn + c[2]
    return f_of(tp, fp, fn)


def row(runs: dict, gts: dict, names: list[str], cv: bool) -> dict:
    out = {c: max_f(runs, gts, names, c) for c in CRITERIA}
    if cv:
        out.update({f"cv_{c}": cross_validated(runs, gts, names, c) for c in CRITERIA})
    top = 0
    for n in names:
        s, ok = _hits(runs[n], gts[n], "challenge")
        top += bool(len(s) and ok[int(np.argmax(s))])
    acc = [sum(runs[n]["accepted"]) for n in names]
    out.update(top=top / len(names), n_axes=statistics.mean(len(runs[n]["scores"]) for n in names),
               one_accepted=sum(a == 1 for a in acc) / len(names), n_accepted=statistics.mean(acc),
               seconds=statistics.median(runs[n]["seconds"] for n in names), n=len(names))
    for c in CRITERIA:  # the accepted axes alone
        tp = fp = fn = 0
        for n in names:
            s, ok = _hits(runs[n], gts[n], c)
            keep = np.asarray(runs[n]["accepted"], dtype=bool)
            t = int(ok[keep].sum()) if len(s) else 0
            tp, fp, fn = tp + t, fp + int(keep.sum()) - t, fn + int(gts[n].shape[0]) - t
        out[f"accepted_f_{c}"] = f_of(tp, fp, fn)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dev", type=Path, default=ROOT.parent / "shared/data/images/reflection_single_dev")
    ap.add_argument("--butterflies", type=Path, default=axes_data.BUTTERFLIES)
    ap.add_argument("--nxc-butterflies", type=int, default=10)
    ap.add_argument("--nxc-dev", type=int, default=32, help="nxc on the first N dev photographs by name")
    ap.add_argument("--butterflies-limit", type=int, default=None, help="the first N check butterflies by name")
    ap.add_argument("--version", default=None, help="reuse the cached detections of this code version")
    ap.add_argument("--cache", type=Path, default=Path("/tmp/axes"))
    args = ap.parse_args()
    torch.set_num_threads(1)
    args.cache.mkdir(parents=True, exist_ok=True)
    version = args.version or source_version()
    sets: dict[str, list[tuple[str, Path, torch.Tensor]]] = {}
    if args.dev.is_dir():
        sets["ICCV'17 dev (32)"] = axes_data.load_dev(args.dev)
    if args.butterflies.is_dir():
        items = axes_data.load_butterflies(args.butterflies)
        _, check = axes_data.split_half([n for n, _, _ in items])
        sets["butterflies check"] = [it for it in items if it[0] in set(check)][: args.butterflies_limit]
    load0 = os.getloadavg()[0]
    results: dict = {"version": version, "sets": {}}
    lines = ["# Photograph axes: the axis stage beside imgsym 0.1.0 (same run, same photographs)", "",
             f"`PYTHONPATH=. python benchmarks/bench_axes.py {' '.join(sys.argv[1:])}` "
             f"(code version {version}). One thread; load average {load0:.1f} at the start on 2 shared cores "
             "(times are indicative). Max F pooled: one threshold over all photographs of a set. Thesis criterion "
             "3 deg, 0.025 min(w, h); challenge 10 deg, 20 % of GT length. `torchsym.detect(path)` is the shipped "
             "default, no overrides. nxc (~9 s a photograph) runs on the first "
             f"{args.nxc_dev} dev photographs and the first {args.nxc_butterflies} check butterflies by name only; "
             "rows named 'nxc subset' score every method on exactly those.", ""]
    for set_name, items in sets.items():
        gts = {n: g for n, _, g in items}
        names = [n for n, _, _ in items]
        nxc_names = names[: args.nxc_dev] if set_name.startswith("ICCV") else names[: args.nxc_butterflies]
        runs = {}
        for m in METHODS:
            todo = nxc_names if m == "imgsym nxc" else names
            runs[m] = {n: detect(m, p, args.cache, version) for n, p, _ in items if n in set(todo)}
            print(f"{set_name}: {m} done ({len(todo)})", flush=True)
        subsets = [(set_name, names, [m for m in METHODS if m != "imgsym nxc" or nxc_names == names])]
        if nxc_names != names:
            subsets.append((f"{set_name}, nxc subset ({len(nxc_names)})", nxc_names, list(METHODS)))
        for label, sub, methods in subsets:
            cv = label.startswith("ICCV") and len(sub) >= 2 * N_FOLDS
            rows = {m: row(runs[m], gts, sub, cv) for m in methods}
            results["sets"][label] = rows
            lines += [f"## {label}", "",
                      "| method | max F thesis | max F challenge | " + ("held-out F thesis (4-fold CV) | held-out F challenge | " if cv else "")
                      + "top axis right (challenge) | axes per photo | accepted per photo | one accepted | F of accepted (thesis / challenge) | median s |",
                      "|---|---|---|" + ("---|---|" if cv else "") + "---|---|---|---|---|---|"]
            for m, r in rows.items():
                cvs = f"{r['cv_thesis']:.3f} | {r['cv_challenge']:.3f} | " if cv else ""
                lines.append(f"| {m} | {r['thesis']:.3f} | {r['challenge']:.3f} | {cvs}{r['top']:.2f} | {r['n_axes']:.1f} | "
                             f"{r['n_accepted']:.1f} | {r['one_accepted']:.2f} | {r['accepted_f_thesis']:.3f} / "
                             f"{r['accepted_f_challenge']:.3f} | {r['seconds']:.2f} |")
            lines.append("")
    lines.append(f"Load average at the end: {os.getloadavg()[0]:.1f}.")
    text = "\n".join(lines) + "\n"
    print(text)
    out = ROOT / "benchmarks/results"
    (out / "axes.md").write_text(text)
    (out / "axes.json").write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
