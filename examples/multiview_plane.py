"""Hidden 3D symmetry from several photos (thesis Sec. 5.3)
=========================================================

Six photos of a synthetic facade, none of which shows the symmetry head-on, are
reconstructed by COLMAP; mirrored SIFT descriptors pair 3D points, and the plane that
most pairs agree on is the scene's reflection plane. Pass a folder of your own photos as
the first argument to run on them instead.
"""

import argparse
from pathlib import Path

import torch

import torchsym
from torchsym.multiview.synthetic import symmetric_scene
from torchsym.viz import write_artifacts

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "output")
ap.add_argument("photos", nargs="?", help="a folder of photos of one scene (default: a synthetic scene)")
args = ap.parse_args()
out = args.out
out.mkdir(parents=True, exist_ok=True)
if args.photos:
    photos = args.photos
else:
    photos = symmetric_scene(6, height=360, width=480, generator=torch.Generator().manual_seed(2)).images
result = torchsym.multiview.detect_multiview_plane(photos)
print("found:", result.found, "confidence:", round(result.confidence, 1), "normal:", result.normal.tolist())
print("wrote", [str(p) for p in write_artifacts(result, photos, out, "multiview")])
