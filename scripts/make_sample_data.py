"""Build the embedded demo cloud torchsym/data/chair.ply (seeded; rerun gives the same file).

A chair made of boxes (seat, back, legs, armrests), mirror symmetric about x = 0 by
construction: one half is sampled and mirrored, then a rigid motion puts the plane in a
general position. Usage: python scripts/make_sample_data.py
"""

from __future__ import annotations

from pathlib import Path

import torch

from torchsym.io.write import write_ply
from torchsym.pointcloud.synthetic import SymmetricCloud, _mirror_half, random_rigid_motion

# (centre, half sizes) of the boxes of the chair's right half (x >= 0).
BOXES = [
    ((0.25, 0.0, 0.45), (0.25, 0.25, 0.03)),  # seat half
    ((0.25, 0.24, 0.85), (0.25, 0.02, 0.38)),  # back half
    ((0.45, -0.2, 0.21), (0.03, 0.03, 0.21)),  # front leg
    ((0.45, 0.2, 0.21), (0.03, 0.03, 0.21)),  # back leg
    ((0.48, 0.0, 0.62), (0.02, 0.22, 0.02)),  # armrest
    ((0.48, -0.2, 0.54), (0.02, 0.02, 0.07)),  # armrest post
    ((0.1, 0.24, 1.05), (0.05, 0.03, 0.05)),  # an asymmetric-looking knob, mirrored too
]


def sample_boxes(n: int, gen: torch.Generator) -> torch.Tensor:
    c = torch.tensor([b[0] for b in BOXES], dtype=torch.float64)
    h = torch.tensor([b[1] for b in BOXES], dtype=torch.float64)
    # surface area of each box decides how many points it gets
    area = 8 * (h[:, 0] * h[:, 1] + h[:, 1] * h[:, 2] + h[:, 0] * h[:, 2])
    which = torch.multinomial(area, n, replacement=True, generator=gen)
    u = torch.rand(n, 3, generator=gen, dtype=torch.float64) * 2 - 1
    face_axis = torch.multinomial(torch.stack([h[which, 1] * h[which, 2], h[which, 0] * h[which, 2], h[which, 0] * h[which, 1]], 1), 1, generator=gen).squeeze(1)
    sign = torch.where(torch.rand(n, generator=gen) < 0.5, -1.0, 1.0).double()
    u[torch.arange(n), face_axis] = sign
    pts = c[which] + u * h[which]
    pts[:, 0] = pts[:, 0].abs()  # the half x >= 0 (the seat/back boxes straddle 0)
    return pts


def main() -> None:
    gen = torch.Generator().manual_seed(2024)
    half = sample_boxes(2000, gen)
    cloud: SymmetricCloud = _mirror_half(half, torch.tensor([1.0, 0.0, 0.0], dtype=torch.float64), torch.tensor(0.0, dtype=torch.float64))
    cloud = random_rigid_motion(cloud, translation=0.5, generator=gen)
    out = Path(__file__).resolve().parents[1] / "torchsym" / "data"
    write_ply(out / "chair.ply", cloud.points.float())
    n, b = cloud.normal, cloud.offset
    (out / "chair_plane.txt").write_text(" ".join(f"{float(v):.9f}" for v in [*n.tolist(), float(b)]) + "\n")
    print("wrote", out / "chair.ply", "plane", n.tolist(), float(b))


if __name__ == "__main__":
    main()
