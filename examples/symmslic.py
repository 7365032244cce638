"""Superpixels that keep a reflection symmetry (thesis Ch. 4)
=============================================================

SymmSLIC finds mirror pixel pairs on the boundaries of a photo with two planted symmetric
objects, then grows superpixels so that each one on one side of an object has its mirror
image on the other (same colour in the picture). The union of the mirror pairs is the
symmetric objects' mask, found without a box or a click.
"""

import argparse
from pathlib import Path

import torch

from torchsym.image import symm_slic
from torchsym.image.synthetic import mirrored_objects_image
from torchsym.viz import write_artifacts

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "output")
args = ap.parse_args()
out = args.out
out.mkdir(parents=True, exist_ok=True)
image, axes = mirrored_objects_image(2, height=480, width=640, generator=torch.Generator().manual_seed(3))
result = symm_slic(image, n_superpixels=400)
print(f"{result.n_superpixels} superpixels, {len(result.pairs)} mirror pairs on {len(result.normals)} axes")
print("wrote", [str(p) for p in write_artifacts(result, image, out, "symmslic")])
