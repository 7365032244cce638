"""The symmetry axis of a photo from its corners: PointSymm on images (thesis Sec. 7.4.4)
======================================================================================

The Harris corners of an image with one planted mirror-symmetric object form a 2-D point
set; PointSymm, run inside RANSAC on samples of the corners, finds the reflection that
maps most corners onto corners, and the axis is that reflection's line. The picture
draws the axis and the mirror pairs of corners that support it.

    python examples/image_pointsymm.py [--out examples/output]
"""

import argparse
from pathlib import Path

import torch

from torchsym.image import point_symm_image
from torchsym.image.synthetic import mirrored_objects_image
from torchsym.viz import write_artifacts

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "output")
args = ap.parse_args()
args.out.mkdir(parents=True, exist_ok=True)

image, axes = mirrored_objects_image(1, generator=torch.Generator().manual_seed(4))  # (3, 360, 480)
result = point_symm_image(image)
print(f"{len(result.corners)} corners, {int(result.inliers.sum())} on the axis, score {result.score:.2f}")
print("axis end points (x, y):", [[round(v, 1) for v in p] for p in result.segment.tolist()])
print("planted axis (x1, y1, x2, y2):", [round(v, 1) for v in axes[0].tolist()])
print("wrote", [str(p) for p in write_artifacts(result, image, args.out, "image_pointsymm")])
