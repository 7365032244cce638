"""What limits the SSM on the symmetric GrabCut / Berkeley masks (``bench_segmentation.py``):
the axis chosen, or the score map itself? A probe, not a tuning run (defaults unchanged).

On every image of ``benchmarks/data/symmetric_masks.txt``, the SSM's ROC AUC and F_beta
(beta^2 = 0.09) against the mask (GrabCut's grey band left out), for:

* ``detected``: the solver as configured (``configs/image_symmetry_map.yaml``, one axis);
* ``oracle_spread``: IRS about the mask's own axis (the axis of largest reflection IoU,
  :func:`torchsym.metrics.best_reflection_iou` on the 240-px mask), from 300 exact mirror
  pairs spread over the whole image (the distance term then carries no locality);
* ``oracle_pairs``: IRS about the mask's axis from the detected candidate pairs that agree
  with it (chord within 5 degrees of its normal, ends on opposite sides, distances to it
  within max(3 px, 5 % of the chord)); images with at least 3 such pairs;
* with the exact rigid reflection about the mask's axis (no search): the descriptor term
  of Eq. 3.7 alone (``exact_descriptor``), the colour similarity ``exp(-|I(p) - I(Lp)| /
  0.1)`` blurred by 4 px (``exact_colour``), the indicator "the mirror lies in the image"
  (``exact_inside``); the distance term of Eq. 3.8 to the agreeing pairs alone
  (``distance``) and times the descriptor term (``exact_descriptor_x_distance``), images
  with at least one such pair.

    PYTHONPATH=.:benchmarks python benchmarks/probes/probe_symmetry_map_oracle.py [--limit N]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import cv2
import numpy as np
import torch

import bench_segmentation as bench  # noqa: E402

from torchsym.core.settings import resolve_settings  # noqa: E402
from torchsym.image.symmetry_map import SymmetryMapSettings, symmetry_map  # noqa: E402
from torchsym.image.symmetry_map.descriptors import dense_axis_descriptors  # noqa: E402
from torchsym.image.symmetry_map.estimate import cluster_field  # noqa: E402
from torchsym.image.symmetry_map.patchmatch import candidate_cost, grid_index, grid_xy  # noqa: E402
from torchsym.image.symmetry_map.scores import distance_to_points, symmetry_scores  # noqa: E402
from torchsym.metrics.symmetry_map import ssm_scores  # noqa: E402

KEYS = ("detected", "oracle_spread", "oracle_pairs", "exact_descriptor", "exact_colour", "exact_inside", "distance",
        "exact_descriptor_x_distance")


def mask_axis(obj: np.ndarray) -> tuple[torch.Tensor, float]:
    """The mask's best reflection axis ``n . (x, y) + c = 0`` in full-resolution pixels."""
    n, c = bench.mask_axis(obj)
    return torch.tensor(n, dtype=torch.float32), c


def spread_pairs(n: torch.Tensor, c: float, h: int, w: int, count: int = 300) -> torch.Tensor:
    """``(M, 4)`` exact mirror pairs about the axis, spread over the image (seeded)."""
    p = torch.rand(4 * count, 2, generator=torch.Generator().manual_seed(0)) * torch.tensor([w - 1.0, h - 1.0])
    d = p @ n + c
    q = p - 2 * d[:, None] * n
    ok = (q[:, 0] >= 0) & (q[:, 0] <= w - 1) & (q[:, 1] >= 0) & (q[:, 1] <= h - 1) & (d.abs() > 3)
    return torch.cat([p, q], 1)[ok][:count]


def agreeing(pairs: torch.Tensor, n: torch.Tensor, c: float) -> torch.Tensor:
    """The candidate pairs whose chord agrees with the axis (see the module docstring)."""
    p, q = pairs[:, :2], pairs[:, 2:]
    chord = (p - q).norm(dim=1).clamp_min(1e-6)
    d1, d2 = p @ n + c, q @ n + c
    ok = ((p - q) @ n).abs() / chord > math.cos(math.radians(5.0))
    ok &= (d1 * d2 < 0) & ((d1.abs() - d2.abs()).abs() <= torch.clamp(0.05 * chord, min=3.0))
    return pairs[ok]


def exact_maps(image: torch.Tensor, n: torch.Tensor, c: float, sigma_feature: float) -> dict[str, torch.Tensor]:
    """``(H * W,)`` maps of the exact reflection about the axis (see the module docstring)."""
    _, _, h, w = image.shape
    desc = dense_axis_descriptors(image, n, n_dims=128, stride=1)
    xy = grid_xy(desc, torch.arange(h * w))
    m = xy - 2 * (xy @ n + c)[:, None] * n
    inside = ((m[:, 0] >= 0) & (m[:, 0] <= w - 1) & (m[:, 1] >= 0) & (m[:, 1] <= h - 1)).float()
    q = grid_index(desc, m)
    col = image[0].reshape(image.shape[1], -1)
    diff = cv2.GaussianBlur((col - col[:, q]).norm(dim=0).view(h, w).numpy(), (0, 0), 4)
    return {"exact_descriptor": torch.exp(-candidate_cost(desc, q) / sigma_feature**2) * inside,
            "exact_colour": torch.exp(-torch.from_numpy(diff).reshape(-1) / 0.1) * inside, "exact_inside": inside}


def probe(key: str, path: Path, mask_path: Path, params: dict, settings: SymmetryMapSettings) -> dict:
    obj, band = bench.read_mask(mask_path)
    res = symmetry_map(bench.read_image(path), params)
    img, (h, w) = res.image[None], obj.shape
    keep = torch.from_numpy(~band)

    def score(m: torch.Tensor) -> tuple[float, float]:
        sc = ssm_scores(m.reshape(h, w)[keep][None], torch.from_numpy(obj)[keep][None])
        return sc.auc, sc.f_beta_0_09

    n, c = mask_axis(obj)
    row = {"name": key, "detected": score(res.score_map)}
    row["oracle_spread"] = score(cluster_field(img, spread_pairs(n, c, h, w), settings, torch.Generator().manual_seed(0))[1])
    agree = agreeing(res.pairs, n, c)
    if len(agree) >= 3:
        row["oracle_pairs"] = score(cluster_field(img, agree, settings, torch.Generator().manual_seed(0))[1])
    exact = exact_maps(img, n, c, settings.score.sigma_feature)
    row.update({k: score(v) for k, v in exact.items()})
    if len(agree):
        dist = distance_to_points(h, w, torch.cat([agree[:, :2], agree[:, 2:]]))
        ones = torch.zeros(h * w)
        near = symmetry_scores(ones, dist, h, w, sigma_feature=1.0, sigma_d=settings.score.sigma_d)
        row["distance"] = score(near)
        row["exact_descriptor_x_distance"] = score(exact["exact_descriptor"] * near)
    return row


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ritm", type=Path, default=Path("/work/data/ritm/datasets"))
    ap.add_argument("--bsds", type=Path, default=Path("/work/data/bsds/BSDS500"))
    ap.add_argument("--limit", type=int, default=0)
    ap.add_argument("--out", type=Path, default=bench.ROOT / "benchmarks" / "results")
    args = ap.parse_args()
    torch.set_num_threads(1)
    cv2.setNumThreads(1)
    names = [s.strip() for s in bench.LIST.read_text().splitlines() if s.strip() and not s.startswith("#")]
    names = names[: args.limit] if args.limit else names
    params = {**bench.config_params("image_symmetry_map"), "n_axes": 1}
    settings = resolve_settings(SymmetryMapSettings, params, {})
    masks = {f"{st}/{nm}": p for st, nm, p in bench.mask_paths(args.ritm)}
    rows = []
    for key in names:
        st, nm = key.split("/")
        rows.append(probe(key, bench.image_path(st, nm, args.ritm, args.bsds), masks[key], params, settings))
        print(json.dumps(rows[-1]), flush=True)
    lines = ["# SSM on the symmetric masks: detected axis against the mask's own axis", "",
             "`PYTHONPATH=.:benchmarks python benchmarks/probes/probe_symmetry_map_oracle.py` (rows: the module docstring)", "",
             "| score map | images | AUC | F (beta^2 0.09) |", "|---|---|---|---|"]
    for k in KEYS:
        vals = [r[k] for r in rows if k in r]
        if vals:
            lines.append(f"| {k} | {len(vals)} | {np.mean([v[0] for v in vals]):.3f} | {np.mean([v[1] for v in vals]):.3f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "symmetry_map_oracle.md").write_text(text)
    (args.out / "symmetry_map_oracle.json").write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
