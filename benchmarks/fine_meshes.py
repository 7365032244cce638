"""Full-resolution, irregular versions of the BCICP FAUST / TOSCA shapes, with their ground truth.

Each remeshed (~5,000-vertex) shape is refined on its own surface, so the geometry is the
same piecewise-linear surface and only the resolution and the triangles change:

1. midpoint subdivision with every new vertex placed at a random point of its edge
   (uniform in 30-70 % of its length), each face split into four;
2. a random share of the new faces split into three at a random interior point
   (barycentric weights from Dirichlet(2, 2, 2)), chosen so that the shape ends with a
   vertex count drawn uniformly from ``[20,000, 50,000]``: valences from 3 to over 10 and
   slivers beside well-shaped triangles;
3. the vertices shuffled.

Every vertex of the coarse shape is a vertex of the fine one, so the ground truth carries
across exactly: the symmetric map of a fine vertex is the fine vertex of the mirror of its
nearest coarse vertex, evaluated on the fine copies of the coarse landmarks. Generated
files are cached (``NAME.npz``: ``vertices``, ``faces``, ``gt (V,)``, ``coarse (n,)``; ``NAME.ext.npy``:
the extremity landmarks, coarse indices) and never committed.

    python benchmarks/fine_meshes.py --faust-tosca /work/data/bcicp/Dataset --out /work/data/bcicp_fine
"""

from __future__ import annotations

import argparse
import zlib
from pathlib import Path

import numpy as np
import torch

from torchsym.geometry.mesh import Mesh
from torchsym.io import read_mesh
from torchsym.metrics.mesh import extremity_vertices

SETS = ("FAUST", "TOSCA_Isometric", "TOSCA_nonIsometric")


def refine_irregular(v: np.ndarray, f: np.ndarray, n_target: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``v (n, 3)``, ``f (F, 3)`` refined to about ``n_target`` vertices on the same surface.

    Returns the fine vertices ``(N, 3)``, faces ``(F', 3)`` and ``coarse (n,)``: the fine
    index of every coarse vertex.
    """
    n = v.shape[0]
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)  # (3F, 2)
    uniq, inv = np.unique(edges, axis=0, return_inverse=True)
    inv = inv.ravel()
    t = rng.uniform(0.3, 0.7, size=(uniq.shape[0], 1))
    mids = (1 - t) * v[uniq[:, 0]] + t * v[uniq[:, 1]]  # (E, 3)
    m = n + inv.reshape(3, -1).T  # (F, 3) midpoints of edges 01, 12, 20
    a, b, c = f[:, 0], f[:, 1], f[:, 2]
    f4 = np.concatenate([
        np.stack([a, m[:, 0], m[:, 2]], 1), np.stack([m[:, 0], b, m[:, 1]], 1),
        np.stack([m[:, 2], m[:, 1], c], 1), np.stack([m[:, 0], m[:, 1], m[:, 2]], 1),
    ])
    verts = np.concatenate([v, mids])
    n_split = int(np.clip(n_target - verts.shape[0], 0, f4.shape[0]))
    split = rng.choice(f4.shape[0], size=n_split, replace=False)
    w = rng.dirichlet((2.0, 2.0, 2.0), size=n_split)  # (S, 3)
    centre = np.einsum("sk,skd->sd", w, verts[f4[split]])
    c_idx = verts.shape[0] + np.arange(n_split)
    keep = np.ones(f4.shape[0], bool)
    keep[split] = False
    fs = f4[split]
    f3 = np.concatenate([
        f4[keep], np.stack([fs[:, 0], fs[:, 1], c_idx], 1), np.stack([fs[:, 1], fs[:, 2], c_idx], 1),
        np.stack([fs[:, 2], fs[:, 0], c_idx], 1),
    ])
    verts = np.concatenate([verts, centre])
    perm = rng.permutation(verts.shape[0])  # new position of each vertex
    out_v = np.empty_like(verts)
    out_v[perm] = verts
    return out_v, perm[f3], perm[:n]


def fine_shape(path: Path, out: Path) -> Path:
    """Write (once) the fine version of the BCICP shape ``path`` and its ground truth under ``out``."""
    target = out / f"{path.stem}.npz"
    if target.is_file():
        return target
    mesh = read_mesh(path, dtype=torch.float64)
    v, f = mesh.vertices.numpy(), mesh.faces.numpy()
    rng = np.random.default_rng(zlib.crc32(path.stem.encode()))
    fv, ff, coarse = refine_irregular(v, f, int(rng.integers(20_000, 50_001)), rng)
    corres = path.parent / "corres"
    src = np.loadtxt(corres / f"{path.stem}.vts", dtype=np.int64) - 1
    dst = np.loadtxt(corres / f"{path.stem}.sym.vts", dtype=np.int64) - 1
    gt = np.full(fv.shape[0], -1, dtype=np.int64)
    gt[coarse[src]] = coarse[dst]
    out.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(target, vertices=fv, faces=ff.astype(np.int32), gt=gt, coarse=coarse)
    return target


def extremity(path: Path, out: Path) -> np.ndarray:
    """The (cached) extremity landmarks of the BCICP shape ``path``: coarse vertex indices, the top 5 %
    of its ground-truth vertices by mean geodesic distance (:func:`torchsym.metrics.extremity_vertices`)."""
    target = out / f"{path.stem}.ext.npy"
    if target.is_file():
        return np.load(target)
    mesh = read_mesh(path, dtype=torch.float64)
    src = np.unique(np.loadtxt(path.parent / "corres" / f"{path.stem}.vts", dtype=np.int64) - 1)
    ext = extremity_vertices(mesh, candidates=src).numpy()
    out.mkdir(parents=True, exist_ok=True)
    np.save(target, ext)
    return ext


def load_fine(npz: Path) -> tuple[Mesh, np.ndarray, np.ndarray]:
    """The fine mesh, its ground truth ``(V,)`` (-1 where none) and the fine index of each coarse vertex."""
    d = np.load(npz)
    mesh = Mesh(torch.from_numpy(d["vertices"]), torch.from_numpy(d["faces"].astype(np.int64)))
    return mesh, d["gt"], d["coarse"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--faust-tosca", type=Path, required=True)
    ap.add_argument("--out", type=Path, default=Path("/work/data/bcicp_fine"))
    ap.add_argument("--step", type=int, default=1)
    args = ap.parse_args()
    for which in SETS:
        folder = args.faust_tosca / which / "vtx_5k"
        for path in sorted(folder.glob("*.off"))[:: args.step]:
            print(fine_shape(path, args.out / which), extremity(path, args.out / which).size)


if __name__ == "__main__":
    main()
