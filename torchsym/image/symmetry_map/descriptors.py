"""Dense descriptors at an axis orientation, whose mirror is an exact permutation (Sec. 3.2).

The thesis describes every pixel by the SIFT descriptor ``d_p`` and its mirrored SIFT
descriptor ``m_p``. Per-pixel SIFT through a keypoint API costs seconds per thousand
pixels; here every pixel is described at once, by convolutions, in the frame of the
cluster's axis (a departure from the thesis, which orients each keypoint by its own
gradient: within one cluster the mirror map fixes the orientation, so the axis frame is the
right one and is shared by all pixels):

1. the image gradient ``g`` in the axis frame ``(g . t, g . n)`` (``t`` along the axis,
   ``n`` across it), its angle soft-binned into 8 orientations at multiples of 45 deg
   (linear interpolation between neighbours), weighted by the magnitude;
2. each orientation plane blurred by a Gaussian of ``cell_px / 2`` (isotropic, so it
   needs no rotation) and sampled at the 4 x 4 cell centres ``(c - 1.5) cell_px t +
   (r - 1.5) cell_px n`` around each pixel (bilinear), with SIFT's Gaussian window over
   the cells, in kornia's layout ``o * 16 + r * 4 + c`` (VLFeat's DSIFT with Gaussian
   rather than flat cells);
3. SIFT's normalisation (unit norm, clip at 0.2, unit norm), bin-wise.

Reflecting about the axis sends ``n -> -n``: row ``r -> 3 - r`` and orientation
``o -> -o mod 8``, the same permutation as kornia's SIFT
(:func:`torchsym.features.sift.mirror_permutation`), so ``m_p = d_p[perm]`` exactly.

4. With ``n_dims < 128``, a mirror-equivariant PCA: the descriptor splits into its
   mirror-symmetric part (the ``+1`` eigenspace of the permutation) and antisymmetric
   part (``-1``); each is projected on its own leading second-moment directions. The
   mirrored reduced descriptor is then the reduced descriptor with the antisymmetric
   coordinates negated, exactly, and ``|d_p - m_q|`` is approximated by an orthogonal
   projection (no centring: the distance must stay translation free). Distances cost
   ``n_dims`` instead of 128 multiply-adds per candidate, the bulk of PatchMatch.
"""

from __future__ import annotations

import dataclasses
import math

import torch
import torch.nn.functional as F

from torchsym.features.sift import mirror_permutation

__all__ = ["DenseDescriptors", "dense_axis_descriptors", "mirror_eigenbases"]

N_ORI = 8
N_CELLS = 4


@dataclasses.dataclass(frozen=True)
class DenseDescriptors:
    """Descriptors of the pixels of a grid (every ``stride``-th pixel) in one axis frame.

    Attributes:
        values: ``(Hg * Wg, D)`` float descriptors, grid point ``j * Wg + i`` at pixel
            ``(i * stride, j * stride)``.
        signs: ``(D,)`` float, +1 or -1: the mirrored descriptor is ``values * signs``.
        height: image height.
        width: image width.
        stride: grid step in pixels.
        mirrored: ``(Hg * Wg, D)`` the mirrored descriptors ``values * signs``.
        sq_norms: ``(Hg * Wg,)`` squared norms of the descriptors.
    """

    values: torch.Tensor
    signs: torch.Tensor
    height: int
    width: int
    stride: int
    mirrored: torch.Tensor
    sq_norms: torch.Tensor

    @classmethod
    def pack(cls, values: torch.Tensor, signs: torch.Tensor, height: int, width: int, stride: int = 1) -> DenseDescriptors:
        """Descriptors ``values (Hg * Wg, D)`` with their mirror ``signs (D,)``, the mirrored copy and norms computed."""
        return cls(values, signs, height, width, stride, values * signs, (values * values).sum(1))

    @property
    def grid_shape(self) -> tuple[int, int]:
        """``(Hg, Wg)``: the grid's rows and columns."""
        return (self.height + self.stride - 1) // self.stride, (self.width + self.stride - 1) // self.stride


def _gaussian_blur(x: torch.Tensor, sigma: float) -> torch.Tensor:
    """Separable Gaussian blur of ``x (1, C, H, W)``, reflect padding."""
    radius = max(1, int(math.ceil(3 * sigma)))
    t = torch.arange(-radius, radius + 1, dtype=x.dtype, device=x.device)
    k = torch.exp(-0.5 * (t / sigma) ** 2)
    k = k / k.sum()
    c = x.shape[1]
    x = F.pad(x, (radius, radius, 0, 0), mode="replicate")
    x = F.conv2d(x, k.view(1, 1, 1, -1).expand(c, 1, 1, -1), groups=c)
    x = F.pad(x, (0, 0, radius, radius), mode="replicate")
    return F.conv2d(x, k.view(1, 1, -1, 1).expand(c, 1, -1, 1), groups=c)


def _orientation_planes(gray: torch.Tensor, normal: torch.Tensor) -> torch.Tensor:
    """``(1, 8, H, W)`` gradient magnitude soft-binned by angle in the axis frame."""
    g = F.pad(gray, (1, 1, 1, 1), mode="replicate")
    gx = 0.5 * (g[..., 1:-1, 2:] - g[..., 1:-1, :-2])  # (1, 1, H, W)
    gy = 0.5 * (g[..., 2:, 1:-1] - g[..., :-2, 1:-1])
    nx, ny = float(normal[0]), float(normal[1])
    g_along = -ny * gx + nx * gy  # component along t = (-ny, nx)
    g_across = nx * gx + ny * gy  # component along n
    mag = torch.sqrt(g_along**2 + g_across**2)
    ang = torch.atan2(g_across, g_along)  # (1, 1, H, W), radians
    centres = torch.arange(N_ORI, dtype=gray.dtype, device=gray.device).view(1, -1, 1, 1) * (2 * math.pi / N_ORI)
    diff = torch.remainder(ang - centres + math.pi, 2 * math.pi) - math.pi  # (1, 8, H, W)
    w = torch.clamp(1 - diff.abs() / (2 * math.pi / N_ORI), min=0)
    return w * mag


def _normalise(d: torch.Tensor) -> torch.Tensor:
    """SIFT's normalisation of ``d (128, N)``, column-wise: unit norm, clip at 0.2, unit norm."""
    d = d / d.norm(dim=0, keepdim=True).clamp_min(1e-8)
    d = d.clamp_(max=0.2)
    return d.div_(d.norm(dim=0, keepdim=True).clamp_min(1e-8))


def mirror_eigenbases(perm: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Orthonormal bases ``(D, D+)`` and ``(D, D-)`` of the +1 and -1 eigenspaces of the
    involutive permutation ``perm (D,)``: ``d[perm] = d B+ B+^T - d B- B-^T``."""
    d = perm.numel()
    plus, minus = [], []
    for i in range(d):
        j = int(perm[i])
        if j == i:
            v = torch.zeros(d, dtype=torch.float64)
            v[i] = 1
            plus.append(v)
        elif i < j:
            v = torch.zeros(d, dtype=torch.float64)
            v[i], v[j] = math.sqrt(0.5), math.sqrt(0.5)
            plus.append(v)
            w = v.clone()
            w[j] = -w[j]
            minus.append(w)
    return torch.stack(plus, 1), torch.stack(minus, 1)


def _reduce(desc: torch.Tensor, n_dims: int, generator: torch.Generator) -> tuple[torch.Tensor, torch.Tensor]:
    """Mirror-equivariant PCA of ``desc (128, N)`` to ``n_dims``; returns values ``(N, n_dims)`` and signs."""
    b_plus, b_minus = mirror_eigenbases(mirror_permutation(N_ORI, N_CELLS))
    b_plus = b_plus.to(desc)
    b_minus = b_minus.to(desc)
    sample = desc[:, torch.randperm(desc.shape[1], generator=generator)[:20000].to(desc.device)].T  # (S, 128)
    parts = []
    for basis in (b_plus, b_minus):
        y = sample @ basis  # (S, D+-)
        evals, evecs = torch.linalg.eigh((y.T @ y).double() / max(1, y.shape[0]))
        parts.append((evals.flip(0), (basis.double() @ evecs.flip(1)).to(desc.dtype)))
    order = torch.cat([parts[0][0], parts[1][0]]).argsort(descending=True)[:n_dims]
    n_plus = int((order < parts[0][0].numel()).sum())
    proj = torch.cat([parts[0][1][:, :n_plus], parts[1][1][:, : n_dims - n_plus]], 1)  # (128, n_dims)
    signs = torch.cat([torch.ones(n_plus), -torch.ones(n_dims - n_plus)]).to(desc)
    return (proj.T @ desc).T.contiguous(), signs


def dense_axis_descriptors(
    image: torch.Tensor,
    normal: torch.Tensor,
    *,
    cell_px: float = 4.0,
    n_dims: int = 128,
    stride: int = 1,
    generator: torch.Generator | None = None,
) -> DenseDescriptors:
    """Descriptors of every pixel of ``image`` in the frame of an axis with unit ``normal``.

    Args:
        image: ``(1, C, H, W)`` float image in [0, 1].
        normal: ``(2,)`` unit normal of the axis (the direction of its mirror chords).
        cell_px: side of a spatial cell, pixels.
        n_dims: descriptor length (128: the full descriptor; fewer: the mirror-equivariant PCA).
        stride: describe every ``stride``-th pixel in each direction.
        generator: the source of randomness (``torch.Generator``) for the PCA's pixel
            sample; None uses a fresh generator seeded with 0, so the same call gives the same bits.

    Returns:
        :class:`DenseDescriptors` with ``values (Hg * Wg, n_dims)``.
    """
    gen = generator if generator is not None else torch.Generator().manual_seed(0)
    _, c, h, w = image.shape
    gray = image.mean(1, keepdim=True) if c == 3 else image  # (1, 1, H, W)
    planes = _gaussian_blur(_orientation_planes(gray, normal), 0.5 * cell_px)  # (1, 8, H, W)
    nx, ny = float(normal[0]), float(normal[1])
    ys, xs = torch.meshgrid(
        torch.arange(0, h, stride, dtype=image.dtype, device=image.device),
        torch.arange(0, w, stride, dtype=image.dtype, device=image.device),
        indexing="ij",
    )
    hg, wg = xs.shape
    cells = []
    for r in range(N_CELLS):
        for cc in range(N_CELLS):
            v, u = (r - 1.5) * cell_px, (cc - 1.5) * cell_px
            ox, oy = u * -ny + v * nx, u * nx + v * ny  # offset u t + v n
            gx = (xs + ox) * (2.0 / max(w - 1, 1)) - 1
            gy = (ys + oy) * (2.0 / max(h - 1, 1)) - 1
            grid = torch.stack([gx, gy], -1)[None]  # (1, Hg, Wg, 2)
            weight = math.exp(-(u * u + v * v) / (2 * (2 * cell_px) ** 2))
            cells.append(weight * F.grid_sample(planes, grid, mode="bilinear", padding_mode="border", align_corners=True))
    desc = torch.stack(cells, 2)  # (1, 8, 16, Hg, Wg): o, r * 4 + c
    desc = _normalise(desc.reshape(N_ORI * N_CELLS * N_CELLS, hg * wg))  # (128, Hg*Wg)
    if n_dims >= desc.shape[0]:
        perm = mirror_permutation(N_ORI, N_CELLS)
        b_plus, b_minus = mirror_eigenbases(perm)
        proj = torch.cat([b_plus, b_minus], 1).to(desc)
        signs = torch.cat([torch.ones(b_plus.shape[1]), -torch.ones(b_minus.shape[1])]).to(desc)
        return DenseDescriptors.pack((proj.T @ desc).T.contiguous(), signs, h, w, stride)
    values, signs = _reduce(desc, n_dims, gen)
    return DenseDescriptors.pack(values, signs, h, w, stride)
