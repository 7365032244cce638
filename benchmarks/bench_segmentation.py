"""Symmetric-object segmentation against ground-truth masks (thesis Secs. 4.3.1 and 3.3.3).

Data (fetched, never committed): the GrabCut and Berkeley interactive-segmentation sets
of ``SamsungLabs/ritm_interactive_segmentation`` at commit ``c05f992`` (``--ritm``, the
folder holding ``GrabCut/{data_GT, boundary_GT}`` and ``Berkeley/masks``); the Berkeley
images are the BSDS500 images of the same id (``--bsds``, the folder holding
``data/images/{train,val,test}``).

Rule for the symmetric subsets, written down and the list made
(``benchmarks/data/symmetric_masks.txt``, ``--make-list``) before any method was run on
these images; it reads the ground-truth masks only:

* the object: GrabCut mask values 255 and the grey unlabelled band (128) along its
  outline; Berkeley mask channel 0 above 127;
* the mask is shrunk (area interpolation, then > 0.5) so its longer side is 240 px;
* one object: the largest 8-connected component holds at least 90 % of the object's pixels;
* bilateral symmetry: the best IoU of the mask with its reflection
  (:func:`torchsym.metrics.best_reflection_iou`: axes through the centroid every 1
  degree, each shifted across itself by -0.1, -0.05, 0, 0.05, 0.1 times the equivalent
  radius ``sqrt(area / pi)``) is at least 0.85.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np
from scipy import ndimage

from torchsym.metrics.masks import best_reflection_iou

ROOT = Path(__file__).resolve().parents[1]
LIST = ROOT / "benchmarks" / "data" / "symmetric_masks.txt"
RULE_SIDE, RULE_COMPONENT, RULE_IOU = 240, 0.90, 0.85


def mask_paths(ritm: Path) -> list[tuple[str, str, Path]]:
    """``(set, id, mask path)`` of every mask, sorted."""
    out = [("GrabCut", p.stem, p) for p in sorted((ritm / "GrabCut" / "boundary_GT").glob("*.bmp"))]
    out += [("Berkeley", p.stem, p) for p in sorted((ritm / "Berkeley" / "masks").glob("*.png"))]
    return out


def read_mask(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """``(object, ignore)`` bool ``(H, W)``: GrabCut's 255 is the object and its 128 band is
    unlabelled; Berkeley's masks are 0 / 255 (channel 0)."""
    m = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    m = m[..., 0] if m.ndim == 3 else m
    return m > 128, m == 128


def rule(path: Path) -> dict:
    """The selection rule's figures for one mask (see the module docstring)."""
    obj, band = read_mask(path)
    obj = obj | band
    s = RULE_SIDE / max(obj.shape)
    small = cv2.resize(obj.astype(np.float32), None, fx=s, fy=s, interpolation=cv2.INTER_AREA) > 0.5
    comp, n = ndimage.label(small, structure=np.ones((3, 3)))
    share = 0.0 if n == 0 else float(np.bincount(comp.reshape(-1))[1:].max() / small.sum())
    iou, _, _ = best_reflection_iou(small)
    return {"component_share": share, "reflection_iou": iou, "symmetric": share >= RULE_COMPONENT and iou >= RULE_IOU}


def make_list(ritm: Path) -> list[str]:
    names, lines = [], []
    for st, name, path in mask_paths(ritm):
        r = rule(path)
        lines.append(f"{st}/{name} component {r['component_share']:.3f} iou {r['reflection_iou']:.3f} {'*' if r['symmetric'] else ''}")
        print(lines[-1], flush=True)
        if r["symmetric"]:
            names.append(f"{st}/{name}")
    LIST.parent.mkdir(parents=True, exist_ok=True)
    LIST.write_text(
        "# set/id of the masks with one bilaterally symmetric object (rule: benchmarks/bench_segmentation.py docstring)\n"
        + "\n".join(names) + "\n"
    )
    return names


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ritm", type=Path, default=Path("/work/data/ritm/datasets"))
    ap.add_argument("--bsds", type=Path, default=Path("/work/data/bsds/BSDS500"))
    ap.add_argument("--make-list", action="store_true", help="apply the rule to the masks and write the list")
    args = ap.parse_args(argv)
    if args.make_list:
        names = make_list(args.ritm)
        print(f"{len(names)} symmetric masks written to {LIST}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
