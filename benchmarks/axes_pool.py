"""The pool the axis stage's ranking and decision are fitted on (issue 56), and its features.

Sources (none of them the 32 ICCV'17 dev photographs):

- ``butterflies``: the Leeds butterflies whose mask has an axis (``axes_data.load_butterflies``);
- ``bsds_train`` / ``bsds_test``: synthetic near-mirrors made from the BSDS500 train / test
  photographs (``/work/data/bsds``, fetched from the GitHub copy ``BIDS/BSDS500``; validation
  images never): an elliptic region of the photograph with one half mirrored onto the other
  (the subject, its axis the ground truth), then an uneven lighting ramp over it, with odds
  1/2 an occluding patch from elsewhere in the photograph, with odds 1/2 a second, smaller
  mirrored region elsewhere (a distractor: its axis is *not* ground truth, as a hand or a
  leaf in a photograph of a person or a plant), then a mild random perspective and noise;
- ``negatives``: photographs and noise without symmetry: BSDS500 train / test photographs
  shuffled by 40-px blocks, Gaussian-smoothed noise (sigma 2 / 4 / 8) and noise inside a
  constant frame (zero or white, smoothed or not).

For each image the axis stage's candidates and features (``torchsym.image.axes.stage.
candidate_features``, on the content box like the stage itself) are cached under
``/tmp/axes56/pool/<source>/<name>.pt`` with the ground truth; ``fit_axes.py`` fits and
validates on them.

    PYTHONPATH=. python benchmarks/axes_pool.py [--per-source 150]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import torch

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE.parent), str(HERE)]

import axes_data  # noqa: E402

from torchsym.core.random import make_generator  # noqa: E402
from torchsym.image.axes import AxisStageSettings  # noqa: E402
from torchsym.image.axes.border import content_box  # noqa: E402
from torchsym.image.axes.stage import candidate_features  # noqa: E402
from torchsym.image.boundary_cliques import boundary_clique_axes  # noqa: E402
from torchsym.io.read import read_image  # noqa: E402

BSDS = Path("/work/data/bsds/BSDS500/data/images")
POOL = Path("/tmp/axes56/pool")
SOURCES = ("butterflies", "bsds_train", "bsds_test", "negatives")


def _region_mirror(img: np.ndarray, centre: np.ndarray, phi: float, a: float, b: float) -> np.ndarray:
    """``img (H, W, 3)`` with the ellipse about ``centre`` (semi-axes ``a`` along the axis of
    direction ``phi``, ``b`` across) made mirror-symmetric: its negative half copied from the positive."""
    h, w = img.shape[:2]
    u = np.array([math.cos(phi), math.sin(phi)])
    n = np.array([-u[1], u[0]])
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    px, py = xx - centre[0], yy - centre[1]
    t, d = px * u[0] + py * u[1], px * n[0] + py * n[1]
    inside = (t / a) ** 2 + (d / b) ** 2 <= 1
    mx, my = (xx - 2 * d * n[0]).astype(np.float32), (yy - 2 * d * n[1]).astype(np.float32)
    mirror = cv2.remap(img, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    out = img.copy()
    sel = inside & (d < 0)
    out[sel] = mirror[sel]
    return out


def near_mirror(photo: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A synthetic near-mirror from ``photo (H, W, 3)`` float32 in [0, 1]: ``(image, gt (1, 4))``."""
    h, w = photo.shape[:2]
    s = min(h, w)
    a = rng.uniform(0.22, 0.45) * s
    b = a * rng.uniform(0.45, 1.0)
    r = max(a, b)
    centre = np.array([rng.uniform(r, w - r), rng.uniform(r, h - r)])
    phi = rng.uniform(0, math.pi) if rng.random() < 0.5 else math.pi / 2 + rng.normal(0, 0.15)
    img = _region_mirror(photo, centre, phi, a, b)
    u = np.array([math.cos(phi), math.sin(phi)])
    gt = np.concatenate([centre - a * u, centre + a * u])[None]
    if rng.random() < 0.5:  # a second, smaller mirrored region: a distractor
        a2 = a * rng.uniform(0.25, 0.5)
        for _ in range(20):
            c2 = np.array([rng.uniform(a2, w - a2), rng.uniform(a2, h - a2)])
            if np.linalg.norm(c2 - centre) > r + a2:
                img = _region_mirror(img, c2, rng.uniform(0, math.pi), a2, a2 * rng.uniform(0.5, 1.0))
                break
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    v = rng.normal(size=2)
    v /= np.linalg.norm(v)
    ramp = 1 + rng.uniform(0.1, 0.35) * ((xx - centre[0]) * v[0] + (yy - centre[1]) * v[1]) / r
    img = np.clip(img * ramp[..., None], 0, 1)
    if rng.random() < 0.5:  # an occluding patch from elsewhere
        ph, pw = int(rng.uniform(0.2, 0.45) * r), int(rng.uniform(0.2, 0.45) * r)
        sy, sx = int(rng.uniform(0, h - ph)), int(rng.uniform(0, w - pw))
        ty = int(np.clip(centre[1] + rng.uniform(-0.7, 0.7) * r - ph / 2, 0, h - ph))
        tx = int(np.clip(centre[0] + rng.uniform(-0.7, 0.7) * r - pw / 2, 0, w - pw))
        img[ty : ty + ph, tx : tx + pw] = photo[sy : sy + ph, sx : sx + pw]
    src = np.float32([[0, 0], [w, 0], [w, h], [0, h]])
    dst = (src + rng.uniform(-0.05, 0.05, size=(4, 2)) * np.float32([w, h])).astype(np.float32)
    hom = cv2.getPerspectiveTransform(src, dst)
    img = cv2.warpPerspective(img, hom, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    pts = cv2.perspectiveTransform(gt.reshape(1, 2, 2).astype(np.float64), hom).reshape(1, 4)
    img = np.clip(img + rng.normal(0, 0.01, img.shape).astype(np.float32), 0, 1)
    return img, pts


def _read(path: Path) -> np.ndarray:
    return cv2.imread(str(path))[..., ::-1].astype(np.float32) / 255


def _tensor(img: np.ndarray) -> torch.Tensor:
    return torch.from_numpy(np.ascontiguousarray(img)).permute(2, 0, 1).float()


def _smooth(x: np.ndarray, sigma: float) -> np.ndarray:
    return cv2.GaussianBlur(x, (0, 0), sigma, borderType=cv2.BORDER_REFLECT) if sigma > 0 else x


def _norm(x: np.ndarray) -> np.ndarray:
    return (x - x.min()) / max(float(x.max() - x.min()), 1e-6)


def negatives(n: int, rng: np.random.Generator):
    """``(name, image (H, W, 3), gt (0, 4))`` of ``n`` images without symmetry."""
    photos = sorted(BSDS.glob("train/*.jpg")) + sorted(BSDS.glob("test/*.jpg"))
    for k in range(n):
        kind = k % 4
        if kind == 0:  # a photograph shuffled by 40-px blocks (cropped to a multiple)
            p = _read(photos[int(rng.integers(len(photos)))])
            h, w = p.shape[0] // 40 * 40, p.shape[1] // 40 * 40
            tiles = p[:h, :w].reshape(h // 40, 40, w // 40, 40, 3).transpose(0, 2, 1, 3, 4).reshape(-1, 40, 40, 3)
            tiles = tiles[rng.permutation(len(tiles))]
            img = tiles.reshape(h // 40, w // 40, 40, 40, 3).transpose(0, 2, 1, 3, 4).reshape(h, w, 3)
        elif kind == 1:
            img = _norm(_smooth(rng.random((240, 320, 3)).astype(np.float32), (2, 4, 8)[k // 4 % 3]))
        else:  # noise in a constant frame, smoothed or not
            img = np.full((240, 320, 3), float(kind == 3), np.float32)
            img[20:-20, 20:-20] = rng.random((200, 280, 3))
            img = _smooth(img, (0, 2, 4)[k // 4 % 3])
        yield f"neg{k:03d}", np.ascontiguousarray(img), np.zeros((0, 4))


def images(source: str, n: int):
    """``(name, image (C, H, W) tensor, gt (G, 4))`` of a source."""
    rng = np.random.default_rng({"bsds_train": 561, "bsds_test": 562, "negatives": 563}.get(source, 0))
    if source == "butterflies":
        for name, path, gt in axes_data.load_butterflies(every=1)[:n]:
            yield name, read_image(path), gt.numpy()
    elif source in ("bsds_train", "bsds_test"):
        photos = sorted(BSDS.glob(f"{source[5:]}/*.jpg"))
        for k, path in enumerate(photos[:n]):
            img, gt = near_mirror(_read(path), rng)
            yield path.stem, _tensor(img), gt
    else:
        for name, img, gt in negatives(n, rng):
            yield name, _tensor(img), gt


def features(img: torch.Tensor, settings: AxisStageSettings) -> dict:
    """The stage's candidates and features on ``img (C, H, W)``, segments in its pixels."""
    bd = settings.border
    y0, y1, x0, x1 = content_box(img, tolerance=bd.tolerance, margin=bd.margin, min_margin=bd.min_margin)
    crop = img[None, :, y0:y1, x0:x1]
    t0 = time.perf_counter()
    cand = boundary_clique_axes(crop, settings.candidates, generator=make_generator(settings.candidates.seed))
    info: dict = {}
    seg, feats = candidate_features(crop, cand, settings, info)
    seg = seg + torch.tensor([x0, y0, x0, y0], dtype=seg.dtype)
    return {"segments": seg, "features": feats, "size": (int(img.shape[-2]), int(img.shape[-1])),
            "seconds": time.perf_counter() - t0}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-source", type=int, default=150)
    parser.add_argument("--sources", nargs="*", default=list(SOURCES))
    parser.add_argument("--butterflies", type=int, default=400)
    args = parser.parse_args()
    torch.set_num_threads(1)
    settings = AxisStageSettings()
    for source in args.sources:
        out = POOL / source
        out.mkdir(parents=True, exist_ok=True)
        n = args.butterflies if source == "butterflies" else args.per_source
        t0 = time.perf_counter()
        for k, (name, img, gt) in enumerate(images(source, n)):
            file = out / f"{name}.pt"
            if file.exists():
                continue
            rec = features(img, settings)
            rec["gt"] = torch.as_tensor(gt, dtype=torch.float64).reshape(-1, 4)
            torch.save(rec, file)
            if k % 25 == 0:
                print(source, k, f"{time.perf_counter() - t0:.0f} s, load {os.getloadavg()[0]:.1f}", flush=True)


if __name__ == "__main__":
    main()
