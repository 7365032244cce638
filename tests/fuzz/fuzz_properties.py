"""Property-based checks of the entry points added since the first fuzz round (``tests/test_fuzz.py``).

Each property draws an input as a user or a training loop could pass it (random shapes
down to 0 and 1, dtypes, constant, NaN, huge and tiny values, odd settings), calls the
entry point and checks the contract: a result or a :class:`~torchsym.errors.TorchsymError`
(nothing else); finite numbers (and gradients) where a result is due; inputs untouched;
the same seed gives the same bits. ``PROPERTIES`` maps a name to each ``@given`` test;
``tests/fuzz/test_properties.py`` runs them with a short seeded profile, and
``scripts/fuzz.py`` one example per process in a long campaign.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import torch
from hypothesis import assume, event, given
from hypothesis import strategies as st

import torchsym
from torchsym import losses as L
from torchsym.errors import TorchsymError

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
SPECIAL = [math.nan, math.inf, -math.inf, 1e30, -1e30, 1e19, 1e-30, 5e-324, 0.0, -0.0, 3.4e38]
DTYPES = [torch.float32, torch.float64, torch.float16, torch.bfloat16, torch.uint8, torch.int64, torch.bool]


def show(**kw: Any) -> None:
    """Print the case (before running it) when ``FUZZ_SHOW`` is set, so a process killed
    by a crash, a timeout or the memory limit leaves its input in the log."""
    if os.environ.get("FUZZ_SHOW"):
        def brief(v: Any) -> str:
            if isinstance(v, torch.Tensor):
                finite = bool(torch.isfinite(v.float()).all()) if v.numel() else True
                return f"tensor{tuple(v.shape)} {v.dtype} finite={finite}" + (f" {v.flatten()[:6].tolist()}" if v.numel() else "")
            return repr(v)[:300]
        print("CASE", {k: brief(v) for k, v in kw.items()}, file=sys.stderr, flush=True)


def expect(call: Any) -> Any:
    """``call()``'s result, or None when it raised a :class:`TorchsymError` (whose message
    must not be empty); any other exception fails the property."""
    try:
        return call()
    except TorchsymError as exc:
        assert str(exc), f"{type(exc).__name__} without a message"
        event(type(exc).__name__)
        if os.environ.get("FUZZ_SHOW"):
            print("TYPED", type(exc).__name__, str(exc)[:160], file=sys.stderr, flush=True)
        return None


def snapshot(*xs: Any) -> list[Any]:
    return [x.detach().clone() if isinstance(x, torch.Tensor) else None for x in xs]


def _equal(a: torch.Tensor, b: torch.Tensor) -> bool:
    """Same shape, dtype and values (NaN equal to NaN)."""
    if a.shape != b.shape or a.dtype != b.dtype:
        return False
    if a.is_floating_point():
        a, b = a.double(), b.double()
        return bool(((a == b) | (a.isnan() & b.isnan())).all())
    return torch.equal(a, b)


def unchanged(before: list[Any], *xs: Any) -> None:
    for b, x in zip(before, xs):
        if b is not None:
            assert _equal(b, x.detach()), "an input was modified"


def all_finite(obj: Any, where: str = "result") -> None:
    """Every float tensor, array and number reachable in ``obj`` (a dataclass, mapping,
    sequence) is finite."""
    if isinstance(obj, torch.Tensor):
        if obj.is_floating_point() and obj.numel():
            assert bool(torch.isfinite(obj).all()), f"{where}: not finite"
    elif isinstance(obj, np.ndarray):
        if np.issubdtype(obj.dtype, np.floating) and obj.size:
            assert np.isfinite(obj).all(), f"{where}: not finite"
    elif isinstance(obj, float):
        assert math.isfinite(obj), f"{where}: {obj}"
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        for f in dataclasses.fields(obj):
            all_finite(getattr(obj, f.name), f"{where}.{f.name}")
    elif isinstance(obj, dict):
        for k, v in obj.items():
            if not _timing(k):
                all_finite(v, f"{where}.{k}")
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            all_finite(v, f"{where}[{i}]")


def _timing(key: Any) -> bool:
    """A field holding wall-clock times (not compared, not required finite)."""
    return isinstance(key, str) and ("second" in key or "timing" in key or key.endswith("_time"))


def same_bits(a: Any, b: Any, where: str = "result") -> None:
    """``a`` and ``b`` (results of two identical calls) hold the same bits, timings aside."""
    if isinstance(a, torch.Tensor):
        assert isinstance(b, torch.Tensor) and _equal(a.detach(), b.detach()), f"{where} differs"
    elif dataclasses.is_dataclass(a) and not isinstance(a, type):
        for f in dataclasses.fields(a):
            if not _timing(f.name):
                same_bits(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            if not _timing(k):
                same_bits(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            same_bits(x, y, f"{where}[{i}]")
    elif isinstance(a, float) and math.isnan(a):
        assert isinstance(b, float) and math.isnan(b), where
    elif isinstance(a, np.ndarray):
        assert np.array_equal(a, b, equal_nan=True), where
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"


# ------------------------------------------------------------------ strategies


@st.composite
def tensors(draw, shape: tuple[int, ...], dtypes: list[torch.dtype] | None = None, special: bool = True) -> torch.Tensor:
    """A tensor of ``shape``: uniform, constant, or with special values sprinkled in."""
    dtype = draw(st.sampled_from(dtypes or [torch.float32, torch.float64]))
    seed = draw(st.integers(0, 2**16))
    g = torch.Generator().manual_seed(seed)
    how = draw(st.sampled_from(["rand", "rand", "rand", "normal", "const", "special", "scaled"] if special else ["rand", "normal", "const"]))
    n = int(np.prod(shape)) if shape else 1
    if how == "rand":
        t = torch.rand(shape, generator=g, dtype=torch.float64)
    elif how == "normal":
        t = torch.randn(shape, generator=g, dtype=torch.float64)
    elif how == "const":
        t = torch.full(shape, draw(st.sampled_from([0.0, 1.0, 0.5, -1.0])), dtype=torch.float64)
    elif how == "scaled":
        t = torch.rand(shape, generator=g, dtype=torch.float64) * draw(st.sampled_from([1e-30, 1e-8, 1e8, 1e30]))
    else:
        t = torch.rand(shape, generator=g, dtype=torch.float64)
        if n:
            k = draw(st.integers(1, min(n, 3)))
            idx = torch.randint(0, n, (k,), generator=g)
            t.view(-1)[idx] = torch.tensor([draw(st.sampled_from(SPECIAL)) for _ in range(k)], dtype=torch.float64)
    if dtype == torch.uint8:
        return (t.nan_to_num(0, 0, 0).clamp(0, 1) * 255).round().to(torch.uint8)
    if dtype == torch.bool:
        return t.nan_to_num(0) > 0.5
    if dtype == torch.int64:
        return t.nan_to_num(0, 0, 0).clamp(-1e6, 1e6).round().long()
    return t.to(dtype)


def near(default: Any) -> st.SearchStrategy:
    """A setting's value: near its default (mostly), or an odd one."""
    if isinstance(default, bool) or not isinstance(default, (int, float)):
        return settings_value
    factors = st.sampled_from([0.5, 1, 2, 4, 0.25])
    plausible = factors.map(lambda f: type(default)(default * f) if isinstance(default, float) else max(1, int(default * f)))
    return st.one_of(plausible, plausible, settings_value)


settings_value = st.one_of(
    st.integers(-3, 3), st.sampled_from([0, 1, 2, 10**9, -(10**9), 2.5, 0.5, 1e-30, 1e30, math.nan, math.inf, None, True, "x"]),
)


# ------------------------------------------------------------------ losses


@st.composite
def loss_inputs(draw) -> dict[str, Any]:
    b, n, d, k = draw(st.integers(0, 3)), draw(st.integers(0, 7)), draw(st.integers(1, 4)), draw(st.integers(0, 3))
    dt = [draw(st.sampled_from([torch.float32, torch.float64]))]
    points = draw(tensors((b, n, d), dt))
    normal = draw(st.one_of(
        tensors((b, k, d), dt),
        st.sampled_from([0.0, 1e-30, 1e-20, 1e-8, 1e19]).map(lambda v: torch.full((b, k, d), v, dtype=dt[0])),
    ))
    offset = draw(tensors((b, k), dt))
    mask = draw(st.one_of(st.none(), tensors((b, n), [torch.bool, torch.float32], special=False)))
    if draw(st.integers(0, 9)) == 0:  # a mismatched shape
        which = draw(st.sampled_from(["normal", "offset", "mask"]))
        bad = draw(st.sampled_from([(b + 1, k, d), (b, k + 1), (b, n + 1), (b,)]))
        if which == "normal":
            normal = torch.zeros(bad)
        elif which == "offset":
            offset = torch.zeros(bad)
        else:
            mask = torch.ones(bad)
    return {"points": points, "normal": normal, "offset": offset, "mask": mask}


def _loss_contract(fn: Any, tensors_in: dict[str, Any], **kw: Any) -> None:
    grads = {name: t.detach().clone().requires_grad_(True) if isinstance(t, torch.Tensor) and t.is_floating_point() and t.dtype in (torch.float32, torch.float64) else t
             for name, t in tensors_in.items()}
    before = snapshot(*grads.values())
    show(fn=fn.__name__, **tensors_in, **kw)
    out = expect(lambda: fn(**grads, **kw))
    unchanged(before, *grads.values())
    if out is None:
        return
    assert isinstance(out, torch.Tensor)
    all_finite(out.detach(), "loss")
    if out.requires_grad:
        out.sum().backward()
        for name, t in grads.items():
            if isinstance(t, torch.Tensor) and t.grad is not None:
                assert bool(torch.isfinite(t.grad).all()), f"gradient of {name} not finite"
    again = fn(**{n: (t.detach() if isinstance(t, torch.Tensor) else t) for n, t in grads.items()}, **kw)
    same_bits(out.detach(), again, "loss (twice)")


@given(loss_inputs(), st.sampled_from(["l2", "truncated", "robust", "huber"]), st.sampled_from([0.05, 0.0, 1e-30, 1e30, math.nan, -1.0]),
       st.sampled_from(["none", "mean", "sum"]), st.sampled_from(["auto", "tree", "brute"]))
def prop_symmetry_distance(x, kind, threshold, reduction, method):
    _loss_contract(L.symmetry_distance, x, kind=kind, threshold=threshold, reduction=reduction, method=method)


@given(loss_inputs(), st.sampled_from(["l1", "l2"]), st.sampled_from(["none", "mirror", "source"]))
def prop_field_loss(x, kind, stop):
    def field(p: torch.Tensor) -> torch.Tensor:
        return torch.sin(3 * p).sum(-1)
    _loss_contract(lambda **kw: L.field_symmetry_loss(field, **kw), x, kind=kind, stop_gradient=stop, reduction="mean")


@given(loss_inputs(), st.one_of(st.integers(-1, 9), st.sampled_from([2.5, 10**6, True])), st.sampled_from([0.5, 1.0, 0.0, -1.0, 1e-30, math.inf]))
def prop_prsnet_loss(x, grid, bound):
    p = x["points"]
    surface = p if p.dim() == 3 and p.shape[1] else torch.rand(max(1, p.shape[0]), 3, p.shape[-1], dtype=p.dtype)
    show(grid=grid, bound=bound, surface=surface)
    cp = expect(lambda: L.closest_point_grid(surface, grid, bound if isinstance(bound, float) else 0.5))
    occ = expect(lambda: L.occupancy_grid(surface, grid, bound if isinstance(bound, float) else 0.5))
    if cp is None or occ is None:
        cp = torch.zeros(max(1, p.shape[0]), 2, 2, p.shape[-1]) if p.shape[-1] == 2 else torch.zeros(1, 1)
        occ = torch.zeros(1)
    all_finite(cp, "closest_points")
    all_finite(occ, "occupancy")
    _loss_contract(lambda **kw: L.prsnet_symmetry_loss(closest_points=cp, occupancy=occ, **kw), x, bound=0.5, reduction="sum")


@given(st.integers(0, 3), st.integers(0, 4), st.integers(0, 4), st.data())
def prop_orthogonality_loss(b, k, d, data):
    normal = data.draw(st.one_of(tensors((b, k, d)), st.sampled_from([0.0, 1e-30, 1e19]).map(lambda v: torch.full((b, k, d), v))))
    mask = data.draw(st.one_of(st.none(), tensors((b, k), [torch.bool, torch.float32], special=False), st.just(torch.ones(b + 1, k))))
    _loss_contract(lambda **kw: L.orthogonality_loss(**kw, reduction="mean"), {"normal": normal, "plane_mask": mask})


@given(st.integers(0, 3), st.integers(1, 4), st.integers(0, 5), st.data())
def prop_flip_loss(b, c, w, data):
    shape = (b, c, data.draw(st.integers(0, 4)), w)
    out = data.draw(tensors(shape, [torch.float32, torch.float64, torch.int64]))
    flipped = data.draw(st.one_of(tensors(shape, [out.dtype]), st.just(torch.zeros(b, c + 1, 1, w))))
    dims = data.draw(st.sampled_from([(-1,), (-2, -1), (2,), (3,), (0,), (7,), (1,), "x"]))
    perm = data.draw(st.one_of(st.none(), st.just(torch.arange(c).flip(0)), st.just(torch.arange(c) + 1), st.just(torch.zeros(c))))
    mask = data.draw(st.one_of(st.none(), st.just(torch.ones(b, 1, *shape[2:])), st.just(torch.ones(b, c + 1, *shape[2:]))))
    kw = {"dims": dims, "channel_permutation": perm, "mask": mask, "kind": data.draw(st.sampled_from(["l1", "l2", "l3"])), "reduction": "mean"}
    _loss_contract(L.flip_consistency_loss, {"output": out, "output_flipped": flipped}, **kw)


@given(st.one_of(st.integers(-2, 40), st.sampled_from([2.5, None, "3", True, 10**12])))
def prop_orientation_permutation(n):
    show(n=n)
    out = expect(lambda: L.orientation_flip_permutation(n))
    if out is not None:
        assert sorted(out.tolist()) == list(range(n))


# ------------------------------------------------------------------ images


@st.composite
def images(draw, max_side: int = 48) -> torch.Tensor:
    """Mostly usable images (3 or 1 channels, float in [0, 1] or uint8, sides from 32),
    else any size down to 0, 2 or 4 channels, a batch, any dtype, special values."""
    side = st.one_of(st.integers(0, 40), st.integers(32, max(32, max_side)), st.integers(32, max(32, max_side)))
    h, w = draw(side), draw(side)
    c = draw(st.sampled_from([3, 3, 3, 1, 1, 2, 4]))
    lead = draw(st.sampled_from([(), (), (), (1,), (2,)]))
    shape = (*lead, c, h, w) if draw(st.integers(0, 9)) else (h, w)
    dtypes = [torch.float32] * 4 + [torch.uint8] * 2 + DTYPES
    img = draw(tensors(shape, dtypes))
    if img.is_floating_point() and draw(st.booleans()):  # a structured image: a mirror-symmetric blob
        yy, xx = torch.meshgrid(torch.linspace(-1, 1, h), torch.linspace(-1, 1, w), indexing="ij")
        blob = ((xx.abs() * 1.3 + (yy - 0.1).abs()) < 0.8).to(img.dtype)
        img = blob.expand(img.shape).clone()
    return img


@st.composite
def map_settings(draw) -> dict[str, Any]:
    kw: dict[str, Any] = {}
    if draw(st.booleans()):
        kw["n_axes"] = draw(st.sampled_from([1, 1, 2, 0, None]))
    groups = {
        "score": ["sigma_feature", "sigma_d"], "descriptor": ["cell_px", "n_dims"], "patchmatch": ["max_iters", "stride", "n_samples", "search_radius"],
        "clustering": ["min_support", "tol_px", "eps_theta"], "candidates": ["num_features", "min_pair_distance"],
    }
    defaults = torchsym.SymmetryMapSettings()
    for _ in range(draw(st.integers(0, 2))):
        g = draw(st.sampled_from(sorted(groups)))
        name = draw(st.sampled_from(groups[g]))
        kw.setdefault(g, {})[name] = draw(near(getattr(getattr(defaults, g), name)))
    if draw(st.integers(0, 4)) == 0:
        kw["max_side"] = draw(st.sampled_from([32, 40, 1, None, 10**9]))
    return kw


def _solver_contract(fn: Any, image: Any, kw: dict[str, Any], seed: int) -> Any:
    before = snapshot(image)
    show(fn=fn.__name__, image=image, settings=kw, seed=seed)
    out = expect(lambda: fn(image, generator=torch.Generator().manual_seed(seed), **kw))
    unchanged(before, image)
    if out is None:
        return None
    all_finite(out)
    score = getattr(out, "score", None)
    if isinstance(score, float):
        assert 0.0 <= score <= 1.0, f"score {score}"
    again = fn(image, generator=torch.Generator().manual_seed(seed), **kw)
    same_bits(out, again)
    json.dumps(out.to_dict())
    return out


@given(images(), map_settings(), st.integers(0, 3))
def prop_symmetry_map(image, kw, seed):
    out = _solver_contract(torchsym.symmetry_map, image, kw, seed)
    if out is not None:
        if out.ssm.numel():
            assert float(out.ssm.min()) >= 0.0 and float(out.ssm.max()) <= 1.0, "score map outside [0, 1]"


@given(images(max_side=40), st.sampled_from([4, 8, 16, 3, 0, 2.5]), st.sampled_from([10.0, 1e-30, 1e30, 0.0]),
       st.sampled_from([0.35, 0.0, 1.0, 2.0]), st.integers(0, 2))
def prop_stylize(image, region_px, ruler, min_score, seed):
    m = expect(lambda: torchsym.symmetry_map(image, n_axes=1, generator=torch.Generator().manual_seed(seed)))
    assume(m is not None)
    kw = {"region_px": region_px, "ruler": ruler, "min_score": min_score, "n_slic_iters": 3}
    show(fn="stylize", image=m.image, settings=kw)
    out = expect(lambda: torchsym.stylize(m, **kw))
    if out is not None:
        all_finite(out)
        assert out.image.shape == m.image.shape
        same_bits(out, torchsym.stylize(m, **kw))


@st.composite
def slic_settings(draw) -> dict[str, Any]:
    kw: dict[str, Any] = {}
    defaults = torchsym.SymmSlicSettings()
    for name in draw(st.lists(st.sampled_from(["n_superpixels", "compactness", "max_iters", "tol_shift", "min_mirror_correlation", "min_size_share"]), max_size=2)):
        kw[name] = draw(st.one_of(near(getattr(defaults, name)), st.sampled_from([1, 2, 3, 4, 5, 400])))
    if draw(st.integers(0, 3)) == 0:
        name = draw(st.sampled_from(["curve_length", "n_partners", "sigma", "edge_sigma", "max_axes", "stride", "rho_bin"]))
        kw["pairs"] = {name: draw(near(getattr(defaults.pairs, name)))}
    if "n_superpixels" not in kw:
        kw["n_superpixels"] = draw(st.sampled_from([20, 50, 100]))  # the default 500 is too many for small images
    return kw


@given(images(max_side=72), slic_settings(), st.integers(0, 3),
       st.one_of(st.none(), st.sampled_from([[[1.0, 0.0, -20.0]], [[0.0, 0.0, 1.0]], [[1.0, 0.0, math.nan]], [[1.0, 0.0, -1e30]], [], [[1.0, 2.0]]])))
def prop_symm_slic(image, kw, seed, axes):
    if axes is not None:
        kw = {**kw, "axes": torch.tensor(axes, dtype=torch.float64)}
    out = _solver_contract(torchsym.symm_slic, image, kw, seed)
    if out is not None:
        assert out.labels.shape == image.shape[-2:] and int(out.labels.min()) >= 0


@given(st.integers(0, 4), st.integers(0, 40), st.integers(0, 40), st.sampled_from([1, 3, 2]), st.data())
def prop_multiview_views(v, h, w, c, data):
    from torchsym.multiview.views import as_views

    kind = data.draw(st.sampled_from(["tensor", "list", "files", "folder"]))
    with tempfile.TemporaryDirectory() as tmp:
        if kind in ("tensor", "list"):
            x = data.draw(tensors((v, c, h, w), [torch.float32, torch.uint8]))
            arg = x if kind == "tensor" else list(x.unbind(0)) if v else []
        else:
            import cv2

            paths = []
            for i in range(v):
                p = Path(tmp) / f"v{i}.png"
                if h and w:
                    cv2.imwrite(str(p), np.full((h, w, 3), 100 + i, np.uint8))
                else:
                    p.write_bytes(b"\x89PNG junk")
                paths.append(p)
            arg = tmp if kind == "folder" else paths
        show(kind=kind, v=v, h=h, w=w, c=c)
        out = expect(lambda: as_views(arg))
        if out is not None:
            assert len(out) >= 2
            for img in out.images:
                assert min(img.shape[-2:]) >= 32 and bool(torch.isfinite(img).all())


@given(st.integers(1, 3), st.integers(2, 48), st.integers(2, 48), st.data())
def prop_multiview_detect(v, h, w, data):
    imgs = data.draw(tensors((v, 3, h, w), [torch.float32]))
    _solver_contract(torchsym.detect_multiview_plane, imgs, {"reconstruction": {"max_features": 64}}, data.draw(st.integers(0, 2)))


# ------------------------------------------------------------------ runner


def _record_value(draw) -> Any:
    return draw(st.one_of(
        st.none(), st.integers(-2, 2), st.floats(allow_nan=True), st.text(max_size=4),
        st.lists(st.one_of(st.floats(-2, 2), st.just(math.nan)), max_size=5),
        st.lists(st.lists(st.one_of(st.floats(-1, 1), st.just(math.nan)), min_size=0, max_size=5), max_size=4),
        st.dictionaries(st.sampled_from(["$array", "x"]), st.text(max_size=3), max_size=1),
    ))


@st.composite
def records(draw, kind: str) -> list[Any]:
    fields = {"image": ["axes", "scores", "segment", "score", "image_size"], "pointcloud": ["normal", "offset", "score"],
              "segmentation": ["mask", "score_map"], "mesh": ["map"]}[kind]
    out = []
    for i in range(draw(st.integers(0, 4))):
        if draw(st.integers(0, 9)) == 0:
            out.append(draw(st.sampled_from([None, 3, "rec", [1, 2], {"status": "ok"}])))
            continue
        good = {"image": {"axes": [[10.0, 0.0, 10.0, 20.0]], "scores": [0.9], "image_size": [20, 20]},
                "pointcloud": {"normal": [1.0, 0.0, 0.0], "offset": 0.0, "score": 0.5},
                "segmentation": {"mask": (np.arange(20).reshape(4, 5) % 2 == 0).tolist()},
                "mesh": {"map": [1, 0, 2]}}[kind]
        result = dict(good)
        for _ in range(draw(st.integers(0, 2))):
            result[draw(st.sampled_from(fields))] = _record_value(draw)
        out.append({"input": f"/data/x{i}.{'png' if kind in ('image', 'segmentation') else 'ply'}",
                    "status": draw(st.sampled_from(["ok", "ok", "ok", "error", "crashed", "weird", None])),
                    "result": draw(st.sampled_from([result, result, None, "text", 7]))})
    return out


@given(st.sampled_from(["image", "pointcloud", "segmentation"]), st.data())
def prop_evaluate(kind, data):
    import cv2

    recs = data.draw(records(kind))
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        if kind == "image":
            truth = root / "axes.txt"
            truth.write_text("".join(f"x{i}.png 10 0 10 20\n" for i in range(4)))
        elif kind == "pointcloud":
            truth = root / "planes.jsonl"
            truth.write_text("\n".join(json.dumps({"input": f"x{i}.ply", "normal": [1, 0, 0], "offset": 0.0,
                                                   "box_min": [-1, -1, -1], "box_max": [1, 1, 1]}) for i in range(4)))
        else:
            truth = root / "masks"
            truth.mkdir()
            empty = data.draw(st.booleans())
            for i in range(4):
                m = np.zeros((4, 5), np.uint8)
                if not empty:
                    m[:, :2] = 255
                cv2.imwrite(str(truth / f"x{i}.png"), m)
        show(kind=kind, records=recs)
        before = json.dumps(recs, default=str)
        ev = expect(lambda: torchsym.evaluate(recs, truth))
        assert json.dumps(recs, default=str) == before, "records were modified"
        if ev is not None:
            text = json.dumps(ev.to_dict())
            assert "NaN" not in text and "Infinity" not in text, "a non-finite figure in the evaluation"
            torchsym.runner.format_evaluation(ev)


@given(st.sampled_from(["workers", "threads_per_worker", "retries", "max_in_flight", "connect_timeout", "out", "engine", "max_inline"]),
       settings_value)
def prop_run_options(name, value):
    from torchsym.runner.validate import check_run_options

    with tempfile.TemporaryDirectory() as tmp:
        kw = {"out": str(Path(tmp) / "r.jsonl"), "workers": 2, "threads_per_worker": 1, "retries": 2, "max_in_flight": None,
              "connect_timeout": 5.0}
        if name == "out":
            value = {0: tmp, 1: str(Path(tmp) / "missing" / "r.jsonl"), 2: ""}.get(value, value) if isinstance(value, int) else value
        if name in kw:
            kw[name] = value
            show(**kw)
            expect(lambda: check_run_options(**kw))
        # the run itself, on one small cloud: it returns or raises a typed error, never hangs
        cloud = Path(tmp) / "c.npy"
        np.save(cloud, np.random.default_rng(0).random((60, 3)))
        out = kw["out"] if name == "out" else str(Path(tmp) / "r.jsonl")
        opts = {} if name in ("out", "engine") else {name: value}
        engine = value if name == "engine" else "serial"
        show(name=name, value=value)
        expect(lambda: torchsym.run(CONFIGS / "pointcloud_plane.yaml", [cloud], out, engine=engine, **opts))


# ------------------------------------------------------------------ metrics


@given(st.integers(0, 12), st.integers(0, 12), st.data())
def prop_mask_metrics(h, w, data):
    from torchsym.metrics import segmentation_error, ssm_scores

    mask = data.draw(tensors((h, w), [torch.bool])).numpy()
    obj = data.draw(tensors((h, w), [torch.bool])).numpy()
    show(mask=torch.from_numpy(mask), obj=torch.from_numpy(obj))
    r = expect(lambda: segmentation_error(mask, obj))
    if r is not None:
        all_finite(r)
    score = data.draw(tensors((h, w), [torch.float32]))
    r = expect(lambda: ssm_scores(score, torch.from_numpy(obj)))
    if r is not None:
        for f in ("precision", "recall", "f_beta_0_09", "f_beta_0_3"):
            v = getattr(r, f)
            assert math.isfinite(v), f


@given(st.integers(0, 12), st.integers(0, 12), st.data())
def prop_superpixel_metrics(h, w, data):
    from torchsym.metrics import superpixels as sp

    labels = data.draw(tensors((h, w), [torch.int64, torch.float32, torch.bool]))
    h2, w2 = (h, w) if data.draw(st.integers(0, 4)) else (h + 1, w)
    truth = data.draw(tensors((h2, w2), [torch.int64, torch.uint8]))
    image = data.draw(tensors((3, h, w), [torch.float32]))
    show(labels=labels, truth=truth, image=image)
    for f, args in ((sp.boundary_recall, (labels.numpy(), truth.numpy())), (sp.undersegmentation_error, (labels.numpy(), truth.numpy())),
                    (sp.achievable_segmentation_accuracy, (labels.numpy(), truth.numpy())), (sp.explained_variation, (labels.numpy(), image)),
                    (sp.compactness, (labels.numpy(),)), (sp.mirror_consistency, (labels.numpy(), torch.tensor([1.0, 0.0]), -w / 2))):
        r = expect(lambda: f(*args))
        if r is not None:
            assert math.isfinite(r), f.__name__


def _solver_inputs(kind: str, data) -> Any:
    if kind == "image":
        return data.draw(images(max_side=64))
    n = data.draw(st.one_of(st.integers(0, 8), st.integers(20, 300)))
    d = 3 if kind == "pointcloud" else data.draw(st.integers(1, 8))
    pts = data.draw(tensors((n, d)))
    if data.draw(st.booleans()) and n >= 2 and pts.is_floating_point():  # a mirror-symmetric cloud
        half = pts[: n // 2]
        pts = torch.cat([half, half * torch.tensor([-1.0] + [1.0] * (d - 1), dtype=pts.dtype)])
    return pts


DETECTORS = {
    "reflection_plane": ("pointcloud", torchsym.detect_reflection_plane, torchsym.ReflectionPlaneSettings),
    "pointsymm": ("points", torchsym.point_symm, torchsym.PointSymmSettings),
    "boundary_cliques": ("image", torchsym.boundary_clique_axes, torchsym.BoundaryCliquesSettings),
    "ksymmetry": ("image", torchsym.ksymmetry_axes, torchsym.KSymmetrySettings),
}


def _leaf_settings(cls: Any, prefix: str = "") -> list[tuple[str, Any]]:
    """``(dotted name, default)`` of every setting of ``cls``, nested groups included."""
    out = []
    obj = cls()
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        if dataclasses.is_dataclass(v):
            out += [(f"{prefix}{f.name}.{n}", d) for n, d in _leaf_settings(type(v))]
        elif not f.name.startswith("_"):
            out.append((f"{prefix}{f.name}", v))
    return out


@given(st.sampled_from(sorted(DETECTORS)), st.data(), st.integers(0, 3))
def prop_detector_settings(name, data, seed):
    kind, fn, cls = DETECTORS[name]
    x = _solver_inputs(kind, data)
    leaves = _leaf_settings(cls)
    kw: dict[str, Any] = {}
    for _ in range(data.draw(st.integers(0, 2))):
        key, default = data.draw(st.sampled_from(leaves))
        kw[key] = data.draw(near(default))
    nested: dict[str, Any] = {}
    for key, v in kw.items():  # dotted names to nested overrides
        *path, last = key.split(".")
        node = nested
        for p in path:
            node = node.setdefault(p, {})
        node[last] = v
    if name == "pointsymm_image":
        nested.setdefault("max_side", 64)
    _solver_contract(fn, x, nested, seed)


# ---------------------------------------------------------------- the symmetry group and BOP files (issue 59)

ODD_NUMBERS = [0.05, 1e-3, 0.0, -1.0, math.nan, math.inf, 2.0, 1e30, True, "0.1", None]


@given(st.integers(0, 4), st.sampled_from([1, 2, 3, 4]), st.sampled_from(ODD_NUMBERS), st.one_of(st.integers(-2, 400), st.sampled_from([2.5, 10**9, True, None])),
       st.data())
def prop_symmetry_group(p, d, tol, max_order, data):
    from torchsym.pointcloud import symmetry_group

    normals = data.draw(tensors((p, d), [torch.float32, torch.float64, torch.int64]))
    res = type("R", (), {"normals": normals, "center": torch.zeros(3)})()
    show(normals=normals, tol=tol, max_order=max_order)
    before = snapshot(normals)
    g = expect(lambda: symmetry_group(res, tol=tol, max_order=max_order))
    unchanged(before, normals)
    if g is not None:
        all_finite(g)
        assert g.order <= max_order


def _bop_value(draw) -> Any:
    return draw(st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-3, 3), st.text(max_size=3), st.none(),
                          st.lists(st.floats(-2, 2), max_size=17), st.booleans()))


@st.composite
def bop_entries(draw) -> Any:
    """A models_info.json entry: mostly well formed (rotations about z by 2 pi / n, a
    translation), or with odd parts."""
    if draw(st.integers(0, 9)) == 0:
        return _bop_value(draw)
    entry: dict[str, Any] = {}
    disc = []
    for _ in range(draw(st.integers(0, 3))):
        n = draw(st.sampled_from([1, 2, 3, 4, 6, 12, 300, 7]))
        a = 2 * math.pi / n
        t = [math.cos(a), -math.sin(a), 0.0, draw(st.sampled_from([0.0, 1.5, math.inf, math.nan])),
             math.sin(a), math.cos(a), 0.0, 0.0, 0.0, 0.0, draw(st.sampled_from([1.0, -1.0])), 0.0, 0.0, 0.0, 0.0, 1.0]
        if draw(st.booleans()):
            k = draw(st.integers(0, 15))
            t[k] = _bop_value(draw)
        disc.append(t if draw(st.integers(0, 5)) else t[: draw(st.integers(0, 16))])
    if disc or draw(st.booleans()):
        entry["symmetries_discrete"] = disc if draw(st.integers(0, 7)) else _bop_value(draw)
    if draw(st.booleans()):
        entry["symmetries_continuous"] = [
            {"axis": draw(st.sampled_from([[0, 0, 1], [0, 0, 0], [1, math.nan, 0], [1, 0], "z"])), "offset": [0.0, 0.0, 0.0]}
            if draw(st.integers(0, 4)) else _bop_value(draw)
        ]
    return entry


@given(bop_entries(), st.sampled_from([0.05, 0.01, math.nan, 0.0]))
def prop_group_from_bop(entry, tol):
    from torchsym.pointcloud import group_from_bop

    show(entry=entry, tol=tol)
    g = expect(lambda: group_from_bop(entry, tol=tol))
    if g is not None:
        all_finite(g)
        assert g.order <= 1000
        for r in g.rotations:
            assert float(torch.linalg.det(r[:3, :3])) > 0


@given(st.dictionaries(st.one_of(st.integers(-2, 5), st.text(max_size=3)), bop_entries(), max_size=3), st.booleans())
def prop_models_info_io(entries, to_folder):
    from torchsym.pointcloud import read_models_info, write_models_info

    show(entries=entries, to_folder=to_folder)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) if to_folder else Path(tmp) / "models_info.json"
        out = expect(lambda: write_models_info(path, entries))
        if out is not None:
            text = out.read_text()
            json.loads(text, parse_constant=lambda c: (_ for _ in ()).throw(AssertionError(f"bare {c} written")))
            back = expect(lambda: read_models_info(out))
            assert back is not None and sorted(back) == sorted(int(k) for k in entries)


PROPERTIES = {
    "symmetry_distance": prop_symmetry_distance,
    "field_loss": prop_field_loss,
    "prsnet_loss": prop_prsnet_loss,
    "orthogonality_loss": prop_orthogonality_loss,
    "flip_loss": prop_flip_loss,
    "orientation_permutation": prop_orientation_permutation,
    "symmetry_map": prop_symmetry_map,
    "stylize": prop_stylize,
    "symm_slic": prop_symm_slic,
    "multiview_views": prop_multiview_views,
    "multiview_detect": prop_multiview_detect,
    "evaluate": prop_evaluate,
    "run_options": prop_run_options,
    "mask_metrics": prop_mask_metrics,
    "superpixel_metrics": prop_superpixel_metrics,
    "detector_settings": prop_detector_settings,
    "symmetry_group": prop_symmetry_group,
    "group_from_bop": prop_group_from_bop,
    "models_info_io": prop_models_info_io,
}
