"""Ablation of the intrinsic-symmetry solver's extensions, on shapes held out from their choice.

Front door: not ``torchsym.detect``; an ablation switches settings off one at a time, which the
shipped config does not.

Every extension of ``torchsym.mesh.intrinsic`` (``docs/design/intrinsic.md``) was chosen by
its effect on BCICP FAUST and TOSCA_Isometric. BCICP's TOSCA_nonIsometric shapes (gorillas,
men and others, 24 with symmetric ground truth) were never used to choose anything: they are
the held-out set. For each part, the solver runs with that part switched off, and the
correspondence rate on every vertex and on the extremities (``bench_mesh.py``'s dev protocol)
is compared with the defaults, on the held-out set and, in-sample, on every ``--step``-th
FAUST / TOSCA shape. Results: ``results/mesh_ablation.md`` / ``.json``.

    python benchmarks/ablate_mesh.py --faust-tosca /work/data/bcicp/Dataset [--step 8]
"""

from __future__ import annotations

import argparse
import json
import logging
import time
from pathlib import Path

import numpy as np
import torch

from torchsym.mesh import intrinsic_symmetry
from torchsym.metrics.mesh import correspondence_rate, mesh_rate

from bench_mesh import extremity_rate, faust_tosca  # noqa: E402 (benchmarks/ is on sys.path when run as a script)

log = logging.getLogger("ablate_mesh")
HERE = Path(__file__).resolve().parent

PARTS = {
    "defaults": {},
    "sign hypotheses (signs.n_uncertain = 0)": {"signs.n_uncertain": 0},
    "HKS-only pairing (hypotheses.hks_pairs)": {"hypotheses.hks_pairs": False},
    "orientation-reversing hypothesis (hypotheses.orientation)": {"hypotheses.orientation": False},
    "extrinsic hypothesis (extrinsic.enabled)": {"extrinsic.enabled": False},
    "correction R (correction.enabled)": {"correction.enabled": False},
    "involutive ZoomOut (refine.involution)": {"refine.involution": False},
    "orientation check (refine.orientation_weight = 0)": {"refine.orientation_weight": 0.0},
    "polish (polish.enabled)": {"polish.enabled": False},
    "realignment (realign.enabled)": {"realign.enabled": False},
}
SETS = (("TOSCA_nonIsometric", "held out: TOSCA non-isometric"), ("FAUST", "in-sample: FAUST"), ("TOSCA_Isometric", "in-sample: TOSCA"))


def run(items, parts: dict) -> dict:
    out = {part: [] for part in parts}
    for name, mesh, gt, ext in items:
        for part, overrides in parts.items():
            tic = time.perf_counter()
            res = intrinsic_symmetry(mesh, **overrides)
            row = {"name": name, "rate": correspondence_rate(mesh, res.map, ground_truth=gt).rate,
                   "ext": extremity_rate(mesh, res.map, gt, ext), "time": time.perf_counter() - tic}
            out[part].append(row)
        log.info("%s %s", name, {p: round(out[p][-1]["ext"], 3) for p in parts})
    return out


def summary(rows: list[dict]) -> dict:
    return {"meshes": len(rows), "rate": float(np.mean([r["rate"] for r in rows])),
            "ext": float(np.mean([r["ext"] for r in rows])), "mesh_rate": mesh_rate([r["rate"] for r in rows]),
            "ext_min": float(min(r["ext"] for r in rows))}


def render(results: dict, step: int) -> str:
    lines = [
        "# Ablation of the intrinsic-symmetry solver's extensions",
        "",
        (
            "Each row switches one part off (the rest at defaults). Extremity rate: correspondence rate on the "
            "ground-truth vertices in the top 5 % by mean geodesic distance (`bench_mesh.py`'s dev protocol); "
            "rate: on every ground-truth vertex; mesh rate: meshes above 75 %. Held out: BCICP TOSCA_nonIsometric, "
            f"never used to choose settings; in-sample: every {step}-th FAUST / TOSCA_Isometric shape. Remeshed "
            "(~5,000-vertex) shapes. A part earns its place where its row falls below the defaults on held-out shapes."
        ),
        "",
    ]
    sets = list(results)
    head = "| part switched off | " + " | ".join(f"{s}: extremity % / rate % / mesh rate % (worst extremity %)" for s in sets) + " |"
    lines += [head, "|---|" + "---|" * len(sets)]
    for part in PARTS:
        cells = []
        for s in sets:
            if part not in results[s]:
                cells.append("-")
                continue
            m = summary(results[s][part])
            cells.append(f"{100 * m['ext']:.1f} / {100 * m['rate']:.1f} / {100 * m['mesh_rate']:.0f} ({100 * m['ext_min']:.0f})")
        lines.append(f"| {part} | " + " | ".join(cells) + " |")
    n = {s: len(results[s]["defaults"]) for s in sets}
    lines += ["", "Meshes: " + ", ".join(f"{s} {k}" for s, k in n.items()) + "."]
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--faust-tosca", type=Path, required=True)
    ap.add_argument("--fine", type=Path, default=Path("/work/data/bcicp_fine"), help="cache of the extremity landmarks")
    ap.add_argument("--step", type=int, default=8, help="every N-th in-sample FAUST / TOSCA shape")
    ap.add_argument("--held-out-step", type=int, default=1)
    ap.add_argument("--out", type=Path, default=HERE / "results")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    torch.set_num_threads(1)
    results = {}
    for which, label in SETS:
        step = args.held_out_step if which == "TOSCA_nonIsometric" else args.step
        results[label] = run(faust_tosca(args.faust_tosca, which, step, args.fine), PARTS)
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "mesh_ablation.json").write_text(json.dumps(results, indent=2))
        (args.out / "mesh_ablation.md").write_text(render(results, args.step))
    print(render(results, args.step))


if __name__ == "__main__":
    main()
