"""The symmetry group the planes generate: the reflections, the rotations they compose
to (two planes at ``pi / k`` give a ``k``-fold axis), and the axes of revolution.

Every plane of a bounded shape passes through one fixed point (its centre); the group is
closed about that point, on the linear parts, so that elements of a detected group (each
plane a little off) still meet exactly.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import torch

from torchsym.core.results import Result
from torchsym.errors import InputShapeError, InputValueError
from torchsym.geometry.reflection import reflection_matrix, tangent_basis

__all__ = [
    "MAX_GROUP_ORDER",
    "SymmetryGroup",
    "check_group_args",
    "check_linear",
    "consistent_group",
    "group_from_generators",
    "rotation_axis_angle",
    "snap_generators",
    "symmetry_group",
]

#: the most elements any closure may generate (a 300-fold BOP axis fits; memory stays small)
MAX_GROUP_ORDER = 10000


@dataclasses.dataclass(frozen=True)
class SymmetryGroup(Result):
    """A point group of 3D symmetries about ``center``.

    Attributes:
        elements: ``(G, 4, 4)`` every discrete element (identity first), homogeneous
            transforms acting on ``[x; 1]`` in the model's units.
        rotations: ``(R, 4, 4)`` the proper rotations among them, identity excluded (with
            axes of revolution, the rotations about those axes are left out: they are
            continuous).
        reflections: ``(P, 4, 4)`` the reflections among them.
        axes: ``(K, 3)`` unit directions of the discrete rotation axes; ``orders (K,)``
            their orders (a ``k``-fold axis has ``k - 1`` rotations in ``rotations``).
        continuous_axes: ``(A, 3)`` unit directions of the axes of revolution;
            ``axis_points (A, 3)`` a point on each.
        center: ``(3,)`` the fixed point.
        closed: False when the closure stopped at ``max_order`` elements.
    """

    elements: torch.Tensor
    rotations: torch.Tensor
    reflections: torch.Tensor
    axes: torch.Tensor
    orders: torch.Tensor
    continuous_axes: torch.Tensor
    axis_points: torch.Tensor
    center: torch.Tensor
    closed: bool

    @property
    def order(self) -> int:
        """Discrete elements, the identity included."""
        return int(self.elements.shape[0])


def rotation_axis_angle(matrix: torch.Tensor) -> tuple[torch.Tensor, float]:
    """Unit axis ``(3,)`` (largest-magnitude component positive; ``(1, 0, 0)`` for the
    identity) and angle in ``[0, pi]`` of a rotation ``matrix (3, 3)``, by SciPy's
    rotation vector (stable near 0 and pi)."""
    from scipy.spatial.transform import Rotation

    rotvec = torch.as_tensor(Rotation.from_matrix(matrix.detach().double().cpu().numpy()).as_rotvec(), dtype=matrix.dtype)
    angle = float(rotvec.norm())
    axis = rotvec / angle if angle > 1e-12 else torch.tensor([1.0, 0.0, 0.0], dtype=matrix.dtype)
    k = int(axis.abs().argmax())
    return (axis if float(axis[k]) >= 0 else -axis).to(matrix.device), angle


def _homogeneous(linear: torch.Tensor, center: torch.Tensor) -> torch.Tensor:
    """``(G, 4, 4)``: ``x -> L (x - c) + c`` for each ``linear (G, 3, 3)``."""
    out = torch.zeros(linear.shape[0], 4, 4, dtype=linear.dtype)
    out[:, :3, :3] = linear
    out[:, :3, 3] = center - linear @ center
    out[:, 3, 3] = 1.0
    return out


def check_group_args(max_order: Any, tol: Any) -> tuple[int, float]:
    """``max_order`` an int in [1, 100000] and ``tol`` a finite float in (0, 1]: the
    closure's bounds, checked in one place for every group function.

    Raises:
        InputValueError: either out of range, NaN or of the wrong type.
    """
    if isinstance(max_order, bool) or not isinstance(max_order, (int, np.integer)) or not 1 <= int(max_order) <= MAX_GROUP_ORDER:
        raise InputValueError(f"max_order: expected an int in [1, {MAX_GROUP_ORDER}], got {max_order!r}")
    if isinstance(tol, bool) or not isinstance(tol, (int, float, np.floating)) or not (0.0 < float(tol) <= 1.0):
        raise InputValueError(f"tol: expected a finite number in (0, 1], got {tol!r}")
    return int(max_order), float(tol)


def check_linear(generators: Any, name: str = "generators") -> torch.Tensor:
    """``generators`` as float64 ``(M, 3, 3)`` orthogonal matrices.

    Raises:
        InputShapeError: not ``(M, 3, 3)``.
        InputValueError: NaN or infinite entries, or a matrix that is not orthogonal.
    """
    g = torch.as_tensor(generators)
    if g.dim() != 3 or tuple(g.shape[1:]) != (3, 3):
        raise InputShapeError(f"{name}: expected (M, 3, 3) matrices, got shape {tuple(g.shape)}")
    g = g.to(torch.float64)
    if not bool(torch.isfinite(g).all()):
        raise InputValueError(f"{name}: expected finite entries, got NaN or inf")
    err = (g @ g.transpose(1, 2) - torch.eye(3, dtype=torch.float64)).flatten(1).norm(dim=1)
    if g.shape[0] and float(err.max()) > 1e-3:
        raise InputValueError(f"{name}: expected orthogonal matrices, got one off by {float(err.max()):.3g}")
    return g


def _close(gens: torch.Tensor, max_order: int, tol: float) -> tuple[torch.Tensor, bool]:
    """The breadth-first closure ``(G, 3, 3)`` of ``gens (M, 3, 3)`` (identity first) and
    whether it ended before ``max_order`` elements."""
    elems = torch.eye(3, dtype=torch.float64)[None]
    frontier = elems
    while frontier.shape[0] and gens.shape[0]:
        prod = (gens[:, None] @ frontier[None]).reshape(-1, 3, 3)  # (M F, 3, 3)
        far = torch.cdist(prod.flatten(1), elems.flatten(1)).min(1).values >= tol
        cand = prod[far]
        near = torch.cdist(cand.flatten(1), cand.flatten(1)) < tol  # (C, C)
        new: list[int] = []
        for i in range(cand.shape[0]):
            if not new or not bool(near[i, new].any()):
                new.append(i)
                if elems.shape[0] + len(new) > max_order:
                    return torch.cat([elems, cand[new[:-1]]]), False
        frontier = cand[new]
        elems = torch.cat([elems, frontier])
    return elems, True


def _signed_angle(matrix: torch.Tensor, axis: torch.Tensor) -> float:
    """The angle in [0, 2 pi) of a rotation ``matrix (3, 3)`` about the unit ``axis``."""
    from scipy.spatial.transform import Rotation

    rv = torch.as_tensor(Rotation.from_matrix(matrix.numpy()).as_rotvec(), dtype=torch.float64)
    return float(rv @ axis) % (2 * math.pi)


def group_from_generators(
    generators: torch.Tensor,
    center: torch.Tensor,
    *,
    continuous_axes: torch.Tensor | None = None,
    axis_points: torch.Tensor | None = None,
    max_order: int = 240,
    tol: float = 0.05,
) -> SymmetryGroup:
    """The group generated by ``generators (M, 3, 3)`` (orthogonal linear parts about
    ``center (3,)``), closed by breadth-first products; two elements are one when their
    matrices differ by less than ``tol`` (Frobenius). Rotations about any of
    ``continuous_axes (A, 3)`` are left out of ``rotations`` and ``axes``.

    ``closed`` is True only for a finite group: the closure ended within ``max_order``
    elements and the rotations about each axis are the ``n - 1`` turns by ``2 pi k / n``
    (within ``tol``); generators of an infinite group (two planes 1 rad apart) fill the
    circle up to ``tol`` and are reported ``closed=False``.

    Raises:
        InputShapeError, InputValueError: generators not ``(M, 3, 3)`` orthogonal and
            finite, ``center`` not 3 finite numbers, ``max_order`` or ``tol`` out of range.
    """
    max_order, tol = check_group_args(max_order, tol)
    gens = check_linear(generators)
    center = _check_vectors(center, "center", 1).reshape(3)
    cont = _check_vectors(continuous_axes, "continuous_axes") if continuous_axes is not None else torch.zeros(0, 3, dtype=torch.float64)
    pts = _check_vectors(axis_points, "axis_points") if axis_points is not None else torch.zeros(0, 3, dtype=torch.float64)
    if cont.shape[0] != pts.shape[0]:
        raise InputShapeError(f"axis_points: expected one point per continuous axis ({cont.shape[0]}), got {pts.shape[0]}")
    if cont.shape[0]:
        norms = cont.norm(dim=1, keepdim=True)
        if float(norms.min()) < 1e-12:
            raise InputValueError("continuous_axes: expected nonzero directions, got a zero vector")
        cont = cont / norms
    lin, closed = _close(gens, max_order, tol)
    det = torch.linalg.det(lin)
    rot_idx, axes, angles = [], [], []
    for i in range(1, lin.shape[0]):
        if float(det[i]) <= 0:
            continue
        axis, angle = rotation_axis_angle(lin[i])
        if angle < 1e-6 or any(float((axis @ d).abs()) > math.cos(math.radians(5.0)) for d in cont):
            continue
        rot_idx.append(i)
        axes.append(axis)
        angles.append(angle)
    distinct: list[torch.Tensor] = []
    members: list[list[int]] = []
    for k, axis in enumerate(axes):
        for j, d in enumerate(distinct):
            if float((axis @ d).abs()) > math.cos(math.radians(5.0)):
                members[j].append(k)
                break
        else:
            distinct.append(axis)
            members.append([k])
    # a finite group: the turns about each axis are 2 pi k / n, k = 1 .. n - 1
    # (to a tenth of the angle tol stands for: 1 rad is 7 pi / 22 within 0.0008 rad, and
    # the 21 turns it generates drift 0.017 rad from 2 pi k / 22)
    step = tol / math.sqrt(2.0)  # the angle a Frobenius distance tol stands for
    for d, m in zip(distinct, members):
        n = len(m) + 1
        got = sorted(_signed_angle(lin[rot_idx[k]], d) for k in m)
        want = [2 * math.pi * k / n for k in range(1, n)]
        if 2 * math.pi / n < step or max(abs(a - b) for a, b in zip(got, want)) > 0.1 * step:
            closed = False
    # a reflection is symmetric with trace 1 (a rotoreflection by 36 degrees has trace 0.62)
    refl = [
        i for i in range(lin.shape[0])
        if float(det[i]) < 0 and float((lin[i] - lin[i].T).norm()) < tol and float(torch.trace(lin[i])) > 0.0
    ]
    homog = _homogeneous(lin, center)
    return SymmetryGroup(
        elements=homog,
        rotations=homog[rot_idx] if rot_idx else torch.zeros(0, 4, 4, dtype=torch.float64),
        reflections=homog[refl] if refl else torch.zeros(0, 4, 4, dtype=torch.float64),
        axes=torch.stack(distinct) if distinct else torch.zeros(0, 3, dtype=torch.float64),
        orders=torch.tensor([len(m) + 1 for m in members], dtype=torch.int64),
        continuous_axes=cont,
        axis_points=pts,
        center=center,
        closed=closed,
    )


def _check_vectors(value: Any, name: str, count: int | None = None) -> torch.Tensor:
    """``value`` as float64 ``(K, 3)`` finite vectors (``count`` of them when given)."""
    v = torch.as_tensor(value)
    if v.dim() == 1 and count == 1:
        v = v[None]
    if v.dim() != 2 or v.shape[1] != 3 or (count is not None and v.shape[0] != count):
        raise InputShapeError(f"{name}: expected ({count if count is not None else 'K'}, 3) vectors, got shape {tuple(v.shape)}")
    if not (v.is_floating_point() or v.dtype in (torch.int32, torch.int64)):
        raise InputValueError(f"{name}: expected real numbers, got {v.dtype}")
    v = v.to(torch.float64)
    if not bool(torch.isfinite(v).all()):
        raise InputValueError(f"{name}: expected finite numbers, got NaN or inf")
    return v


def snap_generators(linear: torch.Tensor, axis: torch.Tensor, max_order: int, angle_deg: float = 5.0) -> torch.Tensor:
    """Generators ``linear (M, 3, 3)`` made consistent with a principal ``axis (3,)``:
    a rotation, reflection or rotoreflection whose axis (or normal) lies within
    ``angle_deg`` of ``axis`` gets exactly ``axis``, one within ``angle_deg`` of
    perpendicular is made perpendicular, and each turn is rounded to the nearest
    ``2 pi / k`` (``k <= max_order``) when within ``angle_deg``. Slightly-off detected
    symmetries then close to the finite group they stand for."""
    from scipy.spatial.transform import Rotation

    a = axis.to(torch.float64) / axis.norm()
    cos_t, sin_t = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    out = []
    for lin in linear.to(torch.float64):
        det = float(torch.linalg.det(lin))
        proper = lin if det > 0 else -lin  # an improper element is -1 times a rotation
        rv = torch.as_tensor(Rotation.from_matrix(proper.numpy()).as_rotvec(), dtype=torch.float64)
        angle = float(rv.norm())
        if angle < 1e-9:
            out.append(lin)
            continue
        u = rv / angle
        c = float(u @ a)
        if abs(c) > cos_t:
            u = a if c > 0 else -a
        elif abs(c) < sin_t:
            u = u - c * a
            u = u / u.norm()
        angle = _rational_turn(angle, max_order, math.radians(angle_deg))
        r = torch.as_tensor(Rotation.from_rotvec((u * angle).numpy()).as_matrix(), dtype=torch.float64)
        out.append(r if det > 0 else -r)
    return torch.stack(out) if out else linear.to(torch.float64)


def _rational_turn(angle: float, max_order: int, tol: float) -> float:
    """``angle`` rounded to ``2 pi m / k`` with the least ``k <= 24`` within 0.2 degrees,
    else the least ``k <= max_order`` within ``tol`` (itself when none is): an exact 30 degrees stays 2 pi /
    12 (2 pi / 11 is within 5 degrees of it, and smaller)."""
    for limit, most in ((min(tol, math.radians(0.2)), min(max_order, 24)), (tol, max_order)):
        for k in range(1, most + 1):
            m = round(angle * k / (2 * math.pi))
            if m and abs(2 * math.pi * m / k - angle) < limit:
                return 2 * math.pi * m / k
    return angle


def consistent_group(
    candidates: torch.Tensor,
    center: torch.Tensor,
    *,
    continuous_axes: torch.Tensor | None = None,
    axis_points: torch.Tensor | None = None,
    max_order: int = 240,
    tol: float = 0.05,
    loose: float = 0.2,
    verify: Any = None,
) -> SymmetryGroup:
    """The group generated by ``candidates (M, 3, 3)`` taken greedily in order (the most
    trusted first): a candidate within ``loose`` (Frobenius) of an element already
    generated is implied and skipped, and one whose addition does not close to a finite
    group (:func:`group_from_generators`' ``closed``) is left out, as is one whose new
    elements ``verify (K, 3, 3) -> bool`` refuses (the shape's own test: every element
    of the group, not only the generators, must be a symmetry). The result is always a
    closed group, the largest the trusted candidates agree on."""
    kwargs = dict(continuous_axes=continuous_axes, axis_points=axis_points, max_order=max_order, tol=tol)
    kept = candidates[:0].to(torch.float64)
    grp = group_from_generators(kept, center, **kwargs)
    for lin in candidates.to(torch.float64):
        lins = grp.elements[:, :3, :3]
        if float((lins - lin).flatten(1).norm(dim=1).min()) < loose:
            continue
        trial = group_from_generators(torch.cat([kept, lin[None]]), center, **kwargs)
        if not trial.closed:
            continue
        if verify is not None:
            tl = trial.elements[:, :3, :3]
            new = torch.cdist(tl.flatten(1), lins.flatten(1)).min(1).values >= tol
            if bool(new.any()) and not verify(tl[new]):
                continue
        kept, grp = torch.cat([kept, lin[None]]), trial
    return grp


def symmetry_group(result, *, max_order: int = 240, tol: float = 0.05) -> SymmetryGroup:
    """The symmetry group of a :class:`~torchsym.pointcloud.ReflectionPlanesResult` (or of
    a one-plane result): the closure of its reflections about ``result.center``. An axis
    of revolution adds one plane through it, so that planes across the axis compose with
    it to the half-turns about axes across it; the rotations about the axis itself are
    continuous and reported as the axis. When the detected planes, each a little off, do
    not close to a finite group, they are snapped to the principal axis they imply
    (:func:`snap_generators`) and taken greedily, best first (:func:`consistent_group`).

    Args:
        result: a result with ``normals (P, 3)`` (or ``normal (3,)``), ``center (3,)`` and,
            optionally, ``continuous_axes (A, 3)`` with ``axis_points (A, 3)``.
        max_order: the most discrete elements generated, in [1, ``MAX_GROUP_ORDER``].
        tol: two elements are one within this Frobenius distance of their linear parts,
            in (0, 1].

    Raises:
        InputValueError: ``result`` has no planes to generate from; NaN, infinite or zero
            normals, a non-finite centre; ``max_order`` or ``tol`` out of range.
        InputShapeError: normals not ``(P, 3)``, a centre not ``(3,)``.
    """
    max_order, tol = check_group_args(max_order, tol)
    normals = getattr(result, "normals", None)
    if normals is None:
        if getattr(result, "normal", None) is None:
            raise InputValueError(f"result: expected a reflection-plane result, got {type(result).__name__}")
        normals = torch.as_tensor(result.normal)[None]
    normals = _check_vectors(normals, "result.normals")
    lengths = normals.norm(dim=1, keepdim=True)
    if normals.shape[0] and float(lengths.min()) < 1e-12:
        raise InputValueError("result.normals: expected nonzero normals, got a zero vector")
    normals = normals / lengths if normals.shape[0] else normals
    center = _check_vectors(getattr(result, "center", None) if getattr(result, "center", None) is not None else torch.zeros(3), "result.center", 1).reshape(3)
    cont = _check_vectors(getattr(result, "continuous_axes", torch.zeros(0, 3)), "result.continuous_axes")
    pts = _check_vectors(getattr(result, "axis_points", torch.zeros(0, 3)), "result.axis_points")
    through = tangent_basis(cont / cont.norm(dim=1, keepdim=True))[..., 0] if cont.shape[0] else torch.zeros(0, 3, dtype=torch.float64)
    planes = torch.cat([normals, through])
    gens = reflection_matrix(planes) if planes.shape[0] else torch.zeros(0, 3, 3, dtype=torch.float64)
    kwargs = dict(continuous_axes=cont, axis_points=pts, max_order=max_order, tol=tol)
    grp = group_from_generators(gens, center, **kwargs)
    if grp.closed or grp.axes.shape[0] == 0:
        return grp
    # the turns the best plane makes with each other plane (its error counts once, not
    # twice as between two others), then the planes
    turns = [gens[0] @ gens[j] for j in range(1, len(gens))]
    cands = torch.cat([torch.stack(turns), gens]) if turns else gens
    return consistent_group(snap_generators(cands, principal_axis(grp), max_order), center, **kwargs)


def principal_axis(group: SymmetryGroup) -> torch.Tensor:
    """The axis of ``group`` with the most rotations (its first continuous axis when it
    has one)."""
    if group.continuous_axes.shape[0]:
        return group.continuous_axes[0]
    return group.axes[int(group.orders.argmax())]
