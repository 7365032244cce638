"""Why SymmSLIC's unsupervised mask misses the symmetric objects of the GrabCut and
Berkeley subsets (``bench_segmentation.py``): a probe, not a tuning run (defaults unchanged).

On every image of ``benchmarks/data/symmetric_masks.txt``, SymmSLIC
(``configs/image_symmslic.yaml``) is run twice more:

* with the axis-support gate off (``pairs.min_support = 0``): is an axis then found, and
  does the strongest one agree with the mask's best reflection axis (within 10 degrees,
  and within 10 % of the image diagonal of the mask's centroid)? Its error over all pixels;
* told the mask's best reflection axis (``axes=``): its error over all pixels and the
  share of the image its mask covers (with a given axis the symmetric region is every
  pixel whose mirror lies in the image, so the 4.3.1 mask is that band, not the object).

    PYTHONPATH=.:benchmarks python benchmarks/probes/probe_symmslic_axes.py
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import cv2
import numpy as np
import torch

import bench_segmentation as bench  # noqa: E402

from torchsym.image.symmslic import symm_slic  # noqa: E402
from torchsym.io import read_image  # noqa: E402
from torchsym.metrics.superpixels import segmentation_error  # noqa: E402


def main() -> int:
    torch.set_num_threads(1)
    cv2.setNumThreads(1)
    ritm, bsds = Path("/work/data/ritm/datasets"), Path("/work/data/bsds/BSDS500")
    params = bench.config_params("image_symmslic")
    gate_off = {**params, "pairs": {**params["pairs"], "min_support": 0.0}}
    rows = []
    for st, name, path, mpath in bench.symmetric_items(ritm, bsds):
        obj, band = bench.read_mask(mpath)
        img = read_image(path)
        n, off = bench.mask_axis(obj)
        r0 = symm_slic(img, gate_off)
        p0 = bench.axis_probe(obj, r0.normals, r0.offsets)
        r1 = symm_slic(img, params, known_axes=torch.tensor([[n[0], n[1], off]]))
        agree = p0["axis_found"] and p0["axis_angle_deg"] <= 10 and p0["centroid_distance_px"] <= 0.1 * math.hypot(*obj.shape)
        rows.append({"name": f"{st}/{name}", "gate_off_found": p0["axis_found"], "gate_off_agree": bool(agree),
                     "gate_off_error": segmentation_error(r0.mask.numpy(), obj, ignore=band)["over_image"],
                     "told_axis_error": segmentation_error(r1.mask.numpy(), obj, ignore=band)["over_image"],
                     "told_axis_mask_share": float(r1.mask.float().mean()), "object_share": float(obj.mean())})
        print(rows[-1], flush=True)
    mean = lambda k: float(np.mean([r[k] for r in rows]))  # noqa: E731
    text = "\n".join([
        "# Probe: SymmSLIC's axes on the symmetric GrabCut and Berkeley subsets", "",
        "`PYTHONPATH=.:benchmarks python benchmarks/probes/probe_symmslic_axes.py` (defaults unchanged; see its docstring).", "",
        "| run | images | axis found | axis agrees with the mask's | error / all px | mask share of the image |", "|---|---|---|---|---|---|",
        f"| gate off (pairs.min_support 0) | {len(rows)} | {sum(r['gate_off_found'] for r in rows)} | "
        f"{sum(r['gate_off_agree'] for r in rows)} | {mean('gate_off_error'):.3f} | |",
        f"| told the mask's axis | {len(rows)} | {len(rows)} | {len(rows)} | {mean('told_axis_error'):.3f} | {mean('told_axis_mask_share'):.3f} |",
        "", f"Objects cover {mean('object_share'):.3f} of their images on average (an empty mask's error)."]) + "\n"
    print(text)
    out = bench.ROOT / "benchmarks" / "results"
    (out / "segmentation_probe.md").write_text(text)
    (out / "segmentation_probe.json").write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
