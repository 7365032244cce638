"""Reflection axes in a photograph (thesis Ch. 2)
===============================================

The default image solver pairs boundary samples whose orientations mirror each other
(Eq. 2.9), groups pairs with one axis into dominant cliques (Eq. 2.11), adds the axes of
mirrored-SIFT pairs, and checks every axis by how exactly the image's gradients are
mirrored about it. The picture numbers the three best axes by rank with their score and
draws the mirror pairs of the best one.
"""

import argparse
from pathlib import Path

import torch

from torchsym.image import boundary_clique_axes, ksymmetry_axes
from torchsym.image.synthetic import mirrored_objects_image
from torchsym.io import read_image
from torchsym.viz import write_artifacts

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "output")
args = ap.parse_args()
out = args.out
out.mkdir(parents=True, exist_ok=True)
photo = Path(__file__).resolve().parents[1].parent / "shared/data/images/reflection_single_dev/refs_047.jpg"
if photo.exists():
    image = read_image(photo)
else:  # a synthetic photo with two planted symmetric objects
    image, _ = mirrored_objects_image(2, generator=torch.Generator().manual_seed(1000))
for name, solver in (("boundary_cliques", boundary_clique_axes), ("ksymmetry", ksymmetry_axes)):
    result = solver(image)
    print(f"{name}: {len(result)} axes, best score {float(result.scores[0]):.2f}" if len(result) else f"{name}: none")
    print("wrote", [str(p) for p in write_artifacts(result, image, out, name)])
