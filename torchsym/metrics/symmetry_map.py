"""Evaluation of dense reflection symmetry maps (thesis Secs. 3.3.2-3.3.3).

NMRF: the correspondence rate against the distance threshold ``tau`` over the pixels of
the symmetric region (Fig. 3.7), and SSIM and PSNR of the reconstruction
``Im(p) = S(p) I(f(p))`` against the image (Fig. 3.8; kornia's SSIM, 11 x 11 Gaussian
window). SSM: precision, recall and F_beta of the map thresholded at ``100 / 255``
(Table 3.1), the precision-recall curve over 21 thresholds in steps of ``12.8 / 255``
(Fig. 3.9) and the area under the ROC curve. Table 3.1's figures (P 0.688, R 0.60,
F 0.6794) fit ``beta^2 = 0.09`` (``beta = 0.3``); the saliency literature's F-measure uses
``beta^2 = 0.3``: both are reported, named ``f_beta_0_09`` and ``f_beta_0_3``.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import torch

from torchsym.core.checks import as_tensor
from torchsym.core.results import Result
from torchsym.errors import InputShapeError, InputValueError

__all__ = [
    "SSMScores",
    "nmrf_correspondence_rate",
    "reconstruct_mirror",
    "reconstruction_quality",
    "ssm_scores",
]


def _field(nmrf: Any, name: str) -> torch.Tensor:
    f = as_tensor(nmrf, name).float()
    if f.dim() != 3 or f.shape[-1] != 2:
        raise InputShapeError(f"{name}: expected (H, W, 2) mirror positions (x, y), got {tuple(f.shape)}")
    return f


def _mask(mask: Any, shape: tuple[int, ...], name: str) -> torch.Tensor:
    m = torch.as_tensor(mask)
    if m.dtype != torch.bool:
        raise InputValueError(f"{name}: expected a bool tensor, got dtype {m.dtype}")
    if tuple(m.shape) != tuple(shape):
        raise InputShapeError(f"{name}: expected shape {tuple(shape)}, got {tuple(m.shape)}")
    return m


def nmrf_correspondence_rate(nmrf: Any, truth: Any, mask: Any, taus: Any = (1, 2, 3, 4, 5, 6, 8, 10, 15, 20)) -> torch.Tensor:
    """The fraction of pixels of ``mask`` whose mirror is within ``tau`` pixels of the true one (Sec. 3.3.2).

    Args:
        nmrf: ``(H, W, 2)`` estimated mirror positions ``(x, y)``.
        truth: ``(H, W, 2)`` true mirror positions.
        mask: ``(H, W)`` bool, the symmetric region evaluated.
        taus: ``(T,)`` distance thresholds in pixels; a correspondence is correct when its
            error is below ``tau`` (strictly, as the thesis).

    Returns:
        ``(T,)`` float64 rates in [0, 1]; zeros for an empty mask.
    """
    f, g = _field(nmrf, "nmrf"), _field(truth, "truth")
    if f.shape != g.shape:
        raise InputShapeError(f"truth: expected shape {tuple(f.shape)} like nmrf, got {tuple(g.shape)}")
    m = _mask(mask, f.shape[:2], "mask").to(f.device)
    t = as_tensor(taus, "taus").double().reshape(-1)
    err = (f - g.to(f.device)).norm(dim=-1)[m].double()  # (M,)
    if err.numel() == 0:
        return torch.zeros_like(t)
    return (err[None].cpu() < t[:, None]).double().mean(1)


def reconstruct_mirror(image: Any, nmrf: Any, ssm: Any | None = None) -> torch.Tensor:
    """``Im(p) = S(p) I(f(p))`` (Sec. 3.3.1): each pixel replaced by its mirror pixel (nearest), weighted by the score.

    Args:
        image: ``(C, H, W)`` float image.
        nmrf: ``(H, W, 2)`` mirror positions ``(x, y)``.
        ssm: ``(H, W)`` scores in [0, 1]; None: no weighting.

    Returns:
        ``(C, H, W)`` float.
    """
    img = as_tensor(image, "image").float()
    if img.dim() != 3:
        raise InputShapeError(f"image: expected (C, H, W), got {tuple(img.shape)}")
    f = _field(nmrf, "nmrf").to(img.device)
    c, h, w = img.shape
    if tuple(f.shape[:2]) != (h, w):
        raise InputShapeError(f"nmrf: expected ({h}, {w}, 2) like image, got {tuple(f.shape)}")
    x = f[..., 0].round().clamp(0, w - 1).long()
    y = f[..., 1].round().clamp(0, h - 1).long()
    out = img[:, y, x]  # (C, H, W)
    if ssm is not None:
        s = as_tensor(ssm, "ssm").float().to(img.device)
        if tuple(s.shape) != (h, w):
            raise InputShapeError(f"ssm: expected ({h}, {w}) like image, got {tuple(s.shape)}")
        out = out * s
    return out


def reconstruction_quality(image: Any, nmrf: Any, ssm: Any | None = None, mask: Any | None = None) -> tuple[float, float]:
    """``(SSIM, PSNR in dB)`` of ``Im`` against ``image`` (Sec. 3.3.2), over ``mask (H, W)`` when given.

    SSIM is kornia's (11 x 11 window) averaged over the pixels; PSNR is
    ``10 log10(1 / MSE)`` for images in [0, 1] (inf when identical).
    """
    from kornia.metrics import ssim

    img = as_tensor(image, "image").float()
    rec = reconstruct_mirror(img, nmrf, ssm)
    smap = ssim(img[None], rec[None], 11)[0].mean(0)  # (H, W)
    err = ((img - rec) ** 2).mean(0)  # (H, W)
    if mask is not None:
        m = _mask(mask, img.shape[-2:], "mask").to(img.device)
        if not bool(m.any()):
            return 0.0, 0.0
        smap, err = smap[m], err[m]
    mse = float(err.mean())
    psnr = float("inf") if mse == 0 else float(10 * torch.log10(torch.tensor(1.0 / mse)))
    return float(smap.mean()), psnr


@dataclasses.dataclass(frozen=True)
class SSMScores(Result):
    """Scores of a symmetry score map against a binary ground truth (Sec. 3.3.3).

    Attributes:
        precision: ``|Phi and G| / |Phi|`` at ``threshold`` (1 when nothing is claimed).
        recall: ``|Phi and G| / |G|`` at ``threshold``.
        f_beta_0_09: F_beta with ``beta^2 = 0.09`` (``beta = 0.3``, the thesis's Table 3.1).
        f_beta_0_3: F_beta with ``beta^2 = 0.3`` (the saliency literature's).
        auc: area under the ROC curve (true against false positive rate), exact (by ranks).
        thresholds: ``(21,)`` the PR curve's thresholds ``k * 12.8 / 255``.
        pr_precision: ``(21,)`` precision at each threshold.
        pr_recall: ``(21,)`` recall at each threshold.
        threshold: the threshold of the single-point scores.
    """

    precision: float
    recall: float
    f_beta_0_09: float
    f_beta_0_3: float
    auc: float
    thresholds: torch.Tensor
    pr_precision: torch.Tensor
    pr_recall: torch.Tensor
    threshold: float


def _f_beta(p: float, r: float, beta2: float) -> float:
    return 0.0 if p + r == 0 else (1 + beta2) * p * r / (beta2 * p + r)


def _pr(score: torch.Tensor, truth: torch.Tensor, t: float) -> tuple[float, float]:
    claim = score >= t
    tp = float((claim & truth).sum())
    n_claim, n_true = float(claim.sum()), float(truth.sum())
    return (tp / n_claim if n_claim else 1.0), (tp / n_true if n_true else 1.0)


def _auc(score: torch.Tensor, truth: torch.Tensor) -> float:
    """ROC AUC by the rank-sum (Mann-Whitney) formula, ties counted half."""
    n_pos, n_neg = int(truth.sum()), int((~truth).sum())
    if n_pos == 0 or n_neg == 0:
        return float("nan")
    s = score.double()
    uniq, inverse, counts = torch.unique(s, return_inverse=True, return_counts=True)
    first = torch.cumsum(counts, 0) - counts  # rank (0-based) of each value's first copy
    ranks = (first.double() + (counts.double() + 1) / 2)[inverse]  # average 1-based ranks
    u = float(ranks[truth].sum()) - n_pos * (n_pos + 1) / 2
    return u / (n_pos * n_neg)


def ssm_scores(ssm: Any, truth: Any, *, threshold: float = 100 / 255) -> SSMScores:
    """Precision, recall, F_beta, the 21-point PR curve and ROC AUC of ``ssm`` against ``truth`` (Sec. 3.3.3).

    Args:
        ssm: ``(H, W)`` scores in [0, 1].
        truth: ``(H, W)`` bool ground-truth symmetric region.
        threshold: the score threshold of precision, recall and F (thesis: 100 of 255).

    Returns:
        :class:`SSMScores`.
    """
    s = as_tensor(ssm, "ssm").float()
    if s.dim() != 2:
        raise InputShapeError(f"ssm: expected (H, W), got {tuple(s.shape)}")
    g = _mask(truth, s.shape, "truth").to(s.device)
    s, g = s.reshape(-1), g.reshape(-1)
    p, r = _pr(s, g, threshold)
    ts = torch.arange(21, dtype=torch.float64) * (12.8 / 255)
    curve = [_pr(s, g, float(t)) for t in ts]
    return SSMScores(
        precision=p,
        recall=r,
        f_beta_0_09=_f_beta(p, r, 0.09),
        f_beta_0_3=_f_beta(p, r, 0.3),
        auc=_auc(s, g),
        thresholds=ts,
        pr_precision=torch.tensor([c[0] for c in curve], dtype=torch.float64),
        pr_recall=torch.tensor([c[1] for c in curve], dtype=torch.float64),
        threshold=float(threshold),
    )
