"""Object boundaries as ordered curves, and their sampled orientations (thesis Sec. 2.3.1).

The thesis starts from an ultrametric contour map and notes that any edge detector can
be used. Here:

1. ``edges="canny"`` (the default of :func:`boundary_curves`; the axis detector
   :func:`torchsym.image.boundary_clique_axes` defaults to Edge Drawing): kornia's Canny (Gaussian smoothing, Sobel gradients,
   non-maximum suppression, double threshold) without kornia's iterative hysteresis,
   which is slow on CPU; hysteresis is done exactly in one pass by keeping the
   8-connected components of weak-or-strong pixels that contain a strong pixel
   (``cv2.connectedComponents``). The map is thinned to one pixel
   (``cv2.ximgproc.thinning``).
2. Junctions are removed as in Sec. 2.3.1: a junction pixel has the largest boundary
   strength (gradient magnitude) in its 3 x 3 neighbourhood and at least 4 boundary
   pixels there (itself included); its non-maximal boundary neighbours are cleared. Any
   pixel still with more than two boundary neighbours is cleared too, so every
   8-connected component is a simple curve.
3. Curves are linked by walking each component from an end (our own tracer). The
   alternative ``edges="edge_drawing"`` uses OpenCV contrib's Edge Drawing
   (``cv2.ximgproc.createEdgeDrawing``), which detects edges and returns them already
   linked into ordered chains without branches; junction removal is then not needed.

Each curve is smoothed along its length, resampled by arc length, and cut into
segments of ``segment_length`` pixels centred on boundary samples every ``stride``
pixels; a segment is described by the tangent orientations (mod pi) at ``n_samples``
evenly spaced points (the normals of Eq. 2.9 are these rotated by 90 degrees, and angles
between normals equal angles between tangents).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import torch

__all__ = ["BoundarySegments", "boundary_curves", "boundary_segments", "edge_map", "gradient_tangent", "remove_junctions"]


def edge_map(gray: np.ndarray, *, sigma: float = 2.0, low_threshold: float = 0.05, high_threshold: float = 0.1):
    """Thin binary edge map and gradient magnitude of a grayscale ``(H, W)`` float image in [0, 1].

    Returns ``(edges (H, W) bool, strength (H, W) float32, tangent (H, W) float32)``: the
    thin edge map, the gradient magnitude, and the boundary tangent angle mod pi (the
    gradient direction turned by 90 degrees).
    """
    import cv2
    import kornia

    t = torch.from_numpy(np.ascontiguousarray(gray, dtype=np.float32))[None, None]
    k = max(3, int(2 * round(3 * sigma) + 1))
    with torch.no_grad():
        mag, edges = kornia.filters.canny(
            t, low_threshold, high_threshold, kernel_size=(k, k), sigma=(sigma, sigma), hysteresis=False
        )
        blurred = kornia.filters.gaussian_blur2d(t, (k, k), (sigma, sigma))
        grad = kornia.filters.spatial_gradient(blurred)[0, 0]  # (2, H, W): d/dx, d/dy
    mag = mag[0, 0].numpy()
    e = edges[0, 0].numpy()
    weak_or_strong = (e > 0).astype(np.uint8)
    n, labels = cv2.connectedComponents(weak_or_strong, connectivity=8)
    has_strong = np.zeros(n, dtype=bool)
    has_strong[labels[e >= 0.99]] = True
    has_strong[0] = False
    keep = has_strong[labels].astype(np.uint8) * 255
    thin = cv2.ximgproc.thinning(keep) > 0
    tangent = np.mod(np.arctan2(grad[1].numpy(), grad[0].numpy()) + np.pi / 2, np.pi)
    return thin, mag.astype(np.float32), tangent.astype(np.float32)


def gradient_tangent(gray: np.ndarray, *, sigma: float = 2.0) -> np.ndarray:
    """``(H, W)`` boundary tangent angle mod pi: the direction of the smoothed image gradient turned by 90 deg."""
    import kornia

    t = torch.from_numpy(np.ascontiguousarray(gray, dtype=np.float32))[None, None]
    k = max(3, int(2 * round(3 * sigma) + 1))
    with torch.no_grad():
        grad = kornia.filters.spatial_gradient(kornia.filters.gaussian_blur2d(t, (k, k), (sigma, sigma)))[0, 0]
    return np.mod(np.arctan2(grad[1].numpy(), grad[0].numpy()) + np.pi / 2, np.pi).astype(np.float32)


def _neighbour_count(mask: np.ndarray) -> np.ndarray:
    import cv2

    m = mask.astype(np.float32)
    return cv2.filter2D(m, -1, np.ones((3, 3), np.float32), borderType=cv2.BORDER_CONSTANT).round().astype(np.int32)


def _remove_staircase_corners(edges: np.ndarray) -> np.ndarray:
    """Drop the corner pixels of 4-connected staircases, so a thin curve is minimally 8-connected.

    A pixel whose two set 4-neighbours form an L (north and east, say) while the opposite
    two 4-neighbours and the opposite diagonal are empty only links pixels that are
    already diagonal neighbours; without it, every pixel of the curve has at most two
    neighbours and the junction test of Sec. 2.3.1 sees only real branchings.
    """
    e = np.pad(edges, 1)
    for (dy1, dx1), (dy2, dx2) in (((-1, 0), (0, 1)), ((0, 1), (1, 0)), ((1, 0), (0, -1)), ((0, -1), (-1, 0))):
        c = e[1:-1, 1:-1]
        a = e[1 + dy1 : e.shape[0] - 1 + dy1, 1 + dx1 : e.shape[1] - 1 + dx1]
        b = e[1 + dy2 : e.shape[0] - 1 + dy2, 1 + dx2 : e.shape[1] - 1 + dx2]
        oa = e[1 - dy1 : e.shape[0] - 1 - dy1, 1 - dx1 : e.shape[1] - 1 - dx1]
        ob = e[1 - dy2 : e.shape[0] - 1 - dy2, 1 - dx2 : e.shape[1] - 1 - dx2]
        od = e[1 - dy1 - dy2 : e.shape[0] - 1 - dy1 - dy2, 1 - dx1 - dx2 : e.shape[1] - 1 - dx1 - dx2]
        corner = c & a & b & ~oa & ~ob & ~od
        # remove only one of two adjacent corners: scan order via a checkerboard
        ys, xs = np.nonzero(corner)
        for y, x in zip(ys.tolist(), xs.tolist()):
            yy, xx = y + 1, x + 1
            if e[yy + dy1, xx + dx1] and e[yy + dy2, xx + dx2]:
                e[yy, xx] = False
    return e[1:-1, 1:-1]


def remove_junctions(edges: np.ndarray, strength: np.ndarray) -> np.ndarray:
    """Clear junctions so that every 8-connected component is a simple curve (Sec. 2.3.1).

    Args:
        edges: ``(H, W)`` bool boundary map.
        strength: ``(H, W)`` boundary strength.

    Returns:
        ``(H, W)`` bool map.
    """
    import cv2

    e = _remove_staircase_corners(edges)
    s = np.where(e, strength, -np.inf).astype(np.float32)
    local_max = cv2.dilate(np.where(e, strength, 0).astype(np.float32), np.ones((3, 3), np.uint8))
    count = _neighbour_count(e)  # includes the pixel itself
    junction = e & (count >= 4) & (s >= local_max)
    if junction.any():
        near = cv2.dilate(junction.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
        e &= ~(near & ~junction & (s < local_max))
    # whatever still branches is cleared
    for _ in range(3):
        branch = e & (_neighbour_count(e) > 3)
        if not branch.any():
            break
        e &= ~branch
    return e


_OFFSETS = [(-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)]


def _trace(edges: np.ndarray, min_length: int) -> list[np.ndarray]:
    """Order the pixels of each component of a branch-free map into ``(n, 2)`` x, y chains."""
    h, w = edges.shape
    ys, xs = np.nonzero(edges)
    n = ys.size
    if n == 0:
        return []
    index = -np.ones((h + 2, w + 2), dtype=np.int64)
    index[ys + 1, xs + 1] = np.arange(n)
    nbr = np.stack([index[ys + 1 + dy, xs + 1 + dx] for dy, dx in _OFFSETS], 1)  # (n, 8)
    # prefer 4-neighbours so diagonal shortcuts do not skip pixels
    order = np.array([1, 3, 4, 6, 0, 2, 5, 7])
    nbr = nbr[:, order]
    degree = (nbr >= 0).sum(1)
    visited = np.zeros(n, dtype=bool)
    nbr_list = nbr.tolist()
    chains = []
    starts = list(np.nonzero(degree <= 1)[0]) + list(range(n))
    for s0 in starts:
        if visited[s0]:
            continue
        chain = [s0]
        visited[s0] = True
        cur = s0
        while True:
            nxt = -1
            for j in nbr_list[cur]:
                if j >= 0 and not visited[j]:
                    nxt = j
                    break
            if nxt < 0:
                break
            visited[nxt] = True
            chain.append(nxt)
            cur = nxt
        if len(chain) >= min_length:
            idx = np.asarray(chain)
            chains.append(np.stack([xs[idx], ys[idx]], 1).astype(np.float64))
    return chains


def boundary_curves(
    image: torch.Tensor,
    *,
    edges: str = "canny",
    sigma: float = 2.0,
    low_threshold: float = 0.03,
    high_threshold: float = 0.08,
    min_length: int = 20,
) -> tuple[list[np.ndarray], np.ndarray]:
    """Boundary curves of ``image (1, C, H, W)`` as ordered ``(n, 2)`` pixel chains ``(x, y)``.

    See the module docstring for the two ``edges`` back ends.

    Returns:
        ``(curves, tangent)``: the chains and the ``(H, W)`` boundary tangent angle mod pi
        from the smoothed image gradient (see :func:`edge_map`).
    """
    gray = image[0].float().mean(0).numpy() if image.shape[1] == 3 else image[0, 0].float().numpy()
    if edges == "edge_drawing":
        tangent = gradient_tangent(gray, sigma=sigma)
        import cv2

        ed = cv2.ximgproc.createEdgeDrawing()
        params = cv2.ximgproc.EdgeDrawing.Params()
        params.Sigma = float(sigma)
        params.MinPathLength = int(min_length)
        ed.setParams(params)
        ed.detectEdges(np.clip(gray * 255, 0, 255).astype(np.uint8))
        chains = [np.asarray(s, dtype=np.float64).reshape(-1, 2) for s in ed.getSegments() if len(s) >= min_length]
        return chains, tangent
    e, strength, tangent = edge_map(gray, sigma=sigma, low_threshold=low_threshold, high_threshold=high_threshold)
    e = remove_junctions(e, strength)
    return _trace(e, min_length), tangent


@dataclasses.dataclass(frozen=True)
class BoundarySegments:
    """Boundary samples and the orientations of the curve segments centred on them.

    Attributes:
        points: ``(N, 2)`` float64 segment centres ``(x, y)`` (the boundary pixels ``p_i``).
        angles: ``(N, S)`` float64 tangent angles mod pi at ``S`` points evenly spaced
            along the segment, from one end to the other.
        curve: ``(N,)`` int64 index of the curve each sample lies on.
    """

    points: np.ndarray
    angles: np.ndarray
    curve: np.ndarray

    def __len__(self) -> int:
        return int(self.points.shape[0])


def _smooth(x: np.ndarray, sigma: float) -> np.ndarray:
    r = max(1, int(3 * sigma))
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    pad = np.pad(x, ((r, r), (0, 0)), mode="edge")
    return np.stack([np.convolve(pad[:, d], k, mode="valid") for d in range(x.shape[1])], 1)


def boundary_segments(
    curves: list[np.ndarray],
    tangent: np.ndarray | None = None,
    *,
    segment_length: float = 24.0,
    n_samples: int = 9,
    stride: float = 3.0,
    smooth: float = 2.0,
) -> BoundarySegments:
    """Cut curves into segments of ``segment_length`` pixels (arc length) every ``stride`` pixels.

    Args:
        curves: ordered ``(n, 2)`` chains.
        tangent: ``(H, W)`` tangent angle mod pi from the image gradient, read at the chain
            pixels; None differentiates the smoothed chain instead (noisier on pixel
            staircases).
        segment_length: the thesis's ``q``: length of the segment around each boundary pixel.
        n_samples: orientation samples per segment (the integral of Eq. 2.9 is their mean).
        stride: arc length between consecutive boundary samples.
        smooth: Gaussian smoothing of the chain (pixels) before tangents are taken.
    """
    pts, angs, cid = [], [], []
    half = segment_length / 2
    offs = np.linspace(-half, half, n_samples)
    for c, chain in enumerate(curves):
        p = _smooth(chain, smooth)
        step = np.linalg.norm(np.diff(p, axis=0), axis=1)
        s = np.concatenate([[0.0], np.cumsum(step)])
        if s[-1] < segment_length + 2:
            continue
        if tangent is not None:
            ang = tangent[chain[:, 1].astype(np.int64), chain[:, 0].astype(np.int64)].astype(np.float64)
            tan = np.stack([np.cos(2 * ang), np.sin(2 * ang)], 1)  # doubled angle: mod-pi safe to average
        else:
            tan = np.gradient(p, s, axis=0) if np.all(np.diff(s) > 0) else np.gradient(p, axis=0)
            d = np.arctan2(tan[:, 1], tan[:, 0])
            tan = np.stack([np.cos(2 * d), np.sin(2 * d)], 1)
        centres = np.arange(half + 1, s[-1] - half - 1, stride)
        if centres.size == 0:
            continue
        q = centres[:, None] + offs[None]  # (n, S) arc-length positions
        tx = np.interp(q, s, tan[:, 0])
        ty = np.interp(q, s, tan[:, 1])
        angs.append(np.mod(0.5 * np.arctan2(ty, tx), np.pi))
        pts.append(np.stack([np.interp(centres, s, p[:, 0]), np.interp(centres, s, p[:, 1])], 1))
        cid.append(np.full(centres.size, c, dtype=np.int64))
    if not pts:
        return BoundarySegments(np.zeros((0, 2)), np.zeros((0, n_samples)), np.zeros(0, dtype=np.int64))
    return BoundarySegments(np.concatenate(pts), np.concatenate(angs), np.concatenate(cid))
