"""SIFT keypoints and descriptors through kornia, and the mirrored SIFT descriptor.

Thesis Sec. 2.2.1 follows Loy & Eklundh (2006): a keypoint ``p_i`` has its SIFT
descriptor ``d_i`` and a *mirrored* descriptor ``m_i``, the descriptor of its patch flipped
about the keypoint's orientation axis. For kornia's SIFT layout (``num_ang_bins = 8``
orientation planes of ``4 x 4`` spatial cells, flattened as ``o * 16 + r * 4 + c``) the
mirrored descriptor is an exact permutation of the 128 bins, see
:func:`mirror_permutation`.

Why it is a permutation: kornia samples the patch in the frame of the keypoint's local
affine frame ``A = s R(theta)`` (patch column axis along the orientation). Mirroring the
image horizontally maps ``A`` to ``diag(-1, 1) A = s R(pi - theta) diag(1, -1)``, so the
keypoint of the mirrored image has orientation ``180 deg - theta`` and its patch is the
original patch with its *rows* reversed (a flip about the orientation axis). Reversing
the rows sends a gradient ``(g_x, g_y)`` to ``(g_x, -g_y)``, i.e. the gradient angle
``phi`` to ``-phi``; kornia's orientation bins sit at ``o * 45 deg`` with linear
interpolation between neighbours, so orientation plane ``o`` goes to ``(8 - o) mod 8``,
and spatial row ``r`` to ``3 - r`` (the Gaussian weighting and the pooling kernel are
symmetric). L2 normalisation, clipping and RootSIFT act bin-wise, so they commute with
the permutation. ``tests/features/test_sift.py`` checks it against descriptors computed
on the flipped image.
"""

from __future__ import annotations

import dataclasses
import functools

import kornia.feature as KF
import torch

from torchsym.core.checks import check_image, check_int
from torchsym.core.results import Result
from torchsym.errors import InputShapeError, InputValueError

__all__ = ["SiftFeatures", "detect_sift", "mirror_descriptors", "mirror_permutation"]

#: Smallest height and width kornia's scale space takes: below it the Gaussian padding of
#: its octaves exceeds the image (RuntimeError from inside kornia).
SIFT_MIN_SIDE = 32


@dataclasses.dataclass(frozen=True)
class SiftFeatures(Result):
    """SIFT keypoints of one image.

    Attributes:
        lafs: ``(N, 2, 3)`` kornia local affine frames in input-image pixels.
        points: ``(N, 2)`` keypoint centres ``(x, y)``, origin at the top-left pixel.
        scales: ``(N,)`` keypoint scales in pixels.
        orientations: ``(N,)`` orientations in radians (kornia's LAF convention).
        responses: ``(N,)`` detector responses, all > 0.
        descriptors: ``(N, 128)`` RootSIFT descriptors in ``layout``.
        layout: the descriptors' bin layout (:func:`mirror_permutation`): ``"kornia"``
            or ``"opencv"``.
    """

    lafs: torch.Tensor
    points: torch.Tensor
    scales: torch.Tensor
    orientations: torch.Tensor
    responses: torch.Tensor
    descriptors: torch.Tensor
    layout: str = "kornia"

    def __len__(self) -> int:
        return int(self.points.shape[0])


@functools.lru_cache(maxsize=4)
def _sift_module(num_features: int) -> KF.SIFTFeature:
    return KF.SIFTFeature(num_features=num_features, upright=False, rootsift=True).eval()


def detect_sift(image: torch.Tensor, *, num_features: int = 1000, backend: str = "kornia") -> SiftFeatures:
    """Detect SIFT keypoints and describe them with kornia's ``SIFTFeature`` or OpenCV's SIFT.

    Padded entries (response zero, which kornia returns when fewer than
    ``num_features`` keypoints exist) are dropped. kornia describes ``num_features``
    frames whatever it finds, so the budget is capped at one keypoint per 100 pixels, and
    a constant image returns no keypoints without running the detector.

    Args:
        image: ``(C, H, W)`` or ``(1, C, H, W)`` float image in [0, 1], ``C`` in {1, 3}.
        num_features: the most keypoints kept (strongest responses).
        backend: ``"kornia"`` (default; differentiable pipeline, any device) or
            ``"opencv"`` (``cv2.SIFT``, on the CPU, an order of magnitude faster there;
            orientations in OpenCV's convention, descriptors in its layout, RootSIFT).

    Returns:
        :class:`SiftFeatures` in input-image pixels (on the image's device).

    Example:
        >>> feats = detect_sift(torch.rand(1, 64, 64), num_features=50)
        >>> feats.descriptors.shape[1]
        128
    """
    img = check_image(image, "image", min_size=SIFT_MIN_SIDE)
    if img.shape[0] != 1:
        raise InputShapeError(f"image: expected a single image (C, H, W) or (1, C, H, W), got batch {tuple(img.shape)}")
    num_features = check_int(num_features, "num_features", minimum=1)
    gray = img.float().mean(1, keepdim=True) if img.shape[1] == 3 else img.float()  # (1, 1, H, W)
    budget = min(num_features, max(16, gray.shape[-1] * gray.shape[-2] // 100))
    if backend not in ("kornia", "opencv"):
        raise InputValueError(f"backend: expected 'kornia' or 'opencv', got {backend!r}")
    if backend == "opencv":
        return _detect_opencv(gray[0, 0], budget)
    if float(gray.max() - gray.min()) < 1e-6:
        lafs = torch.zeros(1, 0, 2, 3)
        resp, desc = torch.zeros(1, 0), torch.zeros(1, 0, 128)
    else:
        with torch.no_grad():
            lafs, resp, desc = _sift_module(budget)(gray)
    keep = resp[0] > 0  # (N,)
    lafs, resp, desc = lafs[0, keep], resp[0, keep], desc[0, keep]
    scales = KF.get_laf_scale(lafs[None])[0, :, 0, 0]  # (N,)
    ori = torch.deg2rad(KF.get_laf_orientation(lafs[None])[0, :, 0])  # (N,)
    return SiftFeatures(lafs, lafs[:, :, 2].clone(), scales, ori, resp, desc)


def _detect_opencv(gray: torch.Tensor, budget: int) -> SiftFeatures:
    """:func:`detect_sift` by ``cv2.SIFT`` on ``gray (H, W)`` in [0, 1]: the ``budget``
    strongest keypoints, RootSIFT descriptors in OpenCV's layout."""
    import cv2

    dev = gray.device
    u8 = (gray.detach().float().clamp(0, 1) * 255).round().to(torch.uint8).cpu().numpy()
    kps, desc = (cv2.SIFT_create(nfeatures=budget).detectAndCompute(u8, None) if u8.max() > u8.min() else ((), None))
    if desc is None or len(kps) == 0:
        z = torch.zeros(0, device=dev)
        return SiftFeatures(torch.zeros(0, 2, 3, device=dev), torch.zeros(0, 2, device=dev), z, z, z,
                            torch.zeros(0, 128, device=dev), "opencv")
    kps = kps[:budget]
    pts = torch.tensor([k.pt for k in kps], dtype=torch.float32)  # (N, 2)
    scales = torch.tensor([k.size / 2 for k in kps], dtype=torch.float32)
    ori = torch.deg2rad(torch.tensor([k.angle for k in kps], dtype=torch.float32))
    resp = torch.tensor([max(k.response, 1e-12) for k in kps], dtype=torch.float32)
    d = torch.from_numpy(desc[: len(kps)]).float()
    d = torch.sqrt(d / d.sum(1, keepdim=True).clamp_min(1e-12))  # RootSIFT
    c, s_ = torch.cos(ori) * scales, torch.sin(ori) * scales
    lafs = torch.stack([torch.stack([c, -s_, pts[:, 0]], 1), torch.stack([s_, c, pts[:, 1]], 1)], 1)  # (N, 2, 3)
    return SiftFeatures(*(t.to(dev) for t in (lafs, pts, scales, ori, resp, d)), "opencv")


@functools.lru_cache(maxsize=8)
def mirror_permutation(num_ang_bins: int = 8, num_spatial_bins: int = 4, layout: str = "kornia") -> torch.Tensor:
    """Index permutation taking a SIFT descriptor to its mirrored descriptor.

    ``mirrored = descriptor[..., mirror_permutation()]`` is the descriptor of the patch
    flipped about the keypoint's orientation axis (thesis Sec. 2.2.1, Loy & Eklundh): orientation
    plane ``o -> (-o) mod num_ang_bins``, spatial row ``r -> num_spatial_bins - 1 - r``,
    column unchanged. The permutation is an involution.

    Args:
        num_ang_bins: orientation bins per cell.
        num_spatial_bins: cells per side.
        layout: ``"kornia"`` (bins flattened as ``o * 16 + r * 4 + c``) or ``"opencv"``
            (``(r * 4 + c) * 8 + o``: OpenCV's, COLMAP's and VLFeat's SIFT).

    Returns:
        ``(num_ang_bins * num_spatial_bins**2,)`` int64 indices.
    """
    if layout not in ("kornia", "opencv"):
        raise InputValueError(f"layout: expected 'kornia' or 'opencv', got {layout!r}")
    o = torch.arange(num_ang_bins)
    r = torch.arange(num_spatial_bins)
    c = torch.arange(num_spatial_bins)
    if layout == "kornia":
        oo, rr, cc = torch.meshgrid((-o) % num_ang_bins, num_spatial_bins - 1 - r, c, indexing="ij")
        return (oo * num_spatial_bins**2 + rr * num_spatial_bins + cc).reshape(-1)
    rr, cc, oo = torch.meshgrid(num_spatial_bins - 1 - r, c, (-o) % num_ang_bins, indexing="ij")
    return ((rr * num_spatial_bins + cc) * num_ang_bins + oo).reshape(-1)


def mirror_descriptors(descriptors: torch.Tensor, *, layout: str = "kornia") -> torch.Tensor:
    """Mirrored SIFT descriptors ``(..., 128)`` of ``(..., 128)`` SIFT descriptors in
    ``layout`` (see :func:`mirror_permutation`)."""
    if descriptors.dim() < 1 or descriptors.shape[-1] != 128:
        raise InputShapeError(f"descriptors: expected (..., 128) SIFT descriptors, got {tuple(descriptors.shape)}")
    return descriptors[..., mirror_permutation(layout=layout).to(descriptors.device)]
