"""Learn the reflection plane of a symmetric shape by gradient descent on the symmetry distance.

The shipped chair (4,000 points, turned so that its plane is no axis plane) is centred,
scaled to unit radius and subsampled to 1,000 points. Eight planes start at random
normals through the centre and are trained together for a few hundred Adam steps on
:func:`torchsym.losses.symmetry_distance` (robust kernel: far residuals, from parts with
no mirror under a wrong plane, stop pulling); the plane with the lowest loss is the
answer. Prints the angle and offset errors against the true plane and writes a PNG.

    python examples/learn_plane.py [--steps 300] [--starts 8] [--out examples/output]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import torch

from torchsym.data import sample_plane, sample_pointcloud
from torchsym.geometry import plane_angle
from torchsym.losses import symmetry_distance


def prepare(n_points: int, generator: torch.Generator) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """``(1, n, 3)`` centred, unit-radius chair and its true plane in those coordinates."""
    pts = sample_pointcloud()
    n_true, b_true = sample_plane()
    centre = pts.mean(0)
    scale = (pts - centre).norm(dim=-1).max()
    pts = (pts - centre) / scale
    b_true = (b_true + n_true @ centre) / scale  # n . (s y + c) + b = 0  ->  n . y + (b + n . c) / s = 0
    keep = torch.randperm(pts.shape[0], generator=generator)[:n_points]
    return pts[keep].unsqueeze(0), n_true, b_true


def learn(points: torch.Tensor, starts: int, steps: int, lr: float, generator: torch.Generator):
    """Train ``starts`` planes; returns the normals ``(K, 3)``, offsets ``(K,)``, losses ``(K,)`` and the loss history."""
    normal = torch.randn(1, starts, 3, generator=generator).requires_grad_()
    offset = torch.zeros(1, starts).requires_grad_()
    opt = torch.optim.Adam([normal, offset], lr=lr)
    history = []
    for _ in range(steps):
        opt.zero_grad()
        loss = symmetry_distance(points, normal, offset, kind="robust", threshold=0.1)  # (1, K)
        loss.sum().backward()
        opt.step()
        with torch.no_grad():  # keep the parametrisation unit-length (the loss normalises anyway)
            length = normal.norm(dim=-1, keepdim=True)
            normal /= length
            offset /= length.squeeze(-1)
        history.append(loss.detach()[0])
    final = symmetry_distance(points, normal.detach(), offset.detach(), kind="robust", threshold=0.1)[0]
    return normal.detach()[0], offset.detach()[0], final, torch.stack(history)


def plot(points, normal, n_true, history, best, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(10, 4.5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    p = points[0]
    side = (p @ normal).numpy() > 0
    ax.scatter(*p[side].T.numpy(), s=2, c="tab:blue")
    ax.scatter(*p[~side].T.numpy(), s=2, c="tab:orange")
    ax.set_box_aspect(tuple(float(v) for v in (p.amax(0) - p.amin(0))))
    ax.set_title("chair split by the learned plane")
    ax2 = fig.add_subplot(1, 2, 2)
    for k in range(history.shape[1]):
        ax2.semilogy(history[:, k].numpy(), lw=2.5 if k == best else 0.8, color="k" if k == best else None)
    ax2.set_xlabel("Adam step")
    ax2.set_ylabel("robust symmetry distance")
    ax2.set_title(f"{history.shape[1]} random starts (best in black)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--starts", type=int, default=8)
    ap.add_argument("--points", type=int, default=1000)
    ap.add_argument("--lr", type=float, default=0.02)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "output", help="folder for learn_plane.png")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    png = args.out / "learn_plane.png"
    torch.set_num_threads(1)
    gen = torch.Generator().manual_seed(args.seed)
    points, n_true, b_true = prepare(args.points, gen)
    normal, offset, final, history = learn(points, args.starts, args.steps, args.lr, gen)
    best = int(final.argmin())
    angle = math.degrees(float(plane_angle(normal[best], n_true)))
    sign = 1.0 if float(normal[best] @ n_true) > 0 else -1.0
    offset_err = abs(float(offset[best] * sign - b_true))
    angles = [math.degrees(float(plane_angle(n, n_true))) for n in normal]
    print(f"steps {args.steps}, starts {args.starts}: best start {best}, loss {float(final[best]):.2e}")
    print(f"angle error {angle:.3f} deg, offset error {offset_err:.4f} (unit radius)")
    print("angle error of every start (deg): " + ", ".join(f"{a:.1f}" for a in angles))
    plot(points, normal[best], n_true, history, best, png)
    print(f"wrote {png}")


if __name__ == "__main__":
    main()
