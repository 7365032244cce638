"""Contract tests that every manifold must pass (after geoopt's)."""

from __future__ import annotations

import math

import pytest
import torch

from torchsym.errors import InputValueError
from torchsym.manifolds import (
    Euclidean,
    Manifold,
    PlaneRotations,
    ProductManifold,
    SpecialOrthogonal,
    Stiefel,
)

DT = torch.float64

MANIFOLDS = {
    "so3-qr": SpecialOrthogonal(3),
    "so3-cayley": SpecialOrthogonal(3, "cayley"),
    "so4-polar": SpecialOrthogonal(4, "polar"),
    "so3-exp": SpecialOrthogonal(3, "exp"),
    "so2": SpecialOrthogonal(2),
    "stiefel-qr": Stiefel(5, 2),
    "stiefel-polar": Stiefel(4, 3, "polar"),
    "stiefel-cayley": Stiefel(6, 2, "cayley"),
    "stiefel-exp": Stiefel(5, 3, "exp"),
    "sphere": Stiefel(4, 1),
    "plane": PlaneRotations(4, (1, 3)),
    "euclid": Euclidean(3),
    "euclid-matrix": Euclidean(2, 3),
    "product": ProductManifold(PlaneRotations(3, (0, 2)), PlaneRotations(3, (1, 2)), Euclidean(3)),
}
PARAMS = pytest.mark.parametrize("m", list(MANIFOLDS.values()), ids=list(MANIFOLDS))


def gen(seed: int = 0) -> torch.Generator:
    return torch.Generator().manual_seed(seed)


def _map(fn, *xs):
    if isinstance(xs[0], tuple):
        return tuple(fn(*parts) for parts in zip(*xs))
    return fn(*xs)


def _maxdiff(a, b) -> float:
    if isinstance(a, tuple):
        return max(_maxdiff(x, y) for x, y in zip(a, b))
    return float((a - b).abs().max())


def _scale(c, u):
    return _map(lambda v: c * v, u)


# A smooth test cost f(x) = sum(a x) + 1/2 sum(b^2 x^2) + 0.1 sum(x^3), with its Euclidean derivatives.
def _coeffs(x, seed=3):
    g = gen(seed)
    return _map(lambda v: (torch.randn(v.shape, generator=g, dtype=DT), torch.randn(v.shape, generator=g, dtype=DT)), x)


def _cost(x, co) -> float:
    if isinstance(x, tuple):
        return sum(_cost(xi, ci) for xi, ci in zip(x, co))
    a, b = co
    return float((a * x).sum() + 0.5 * (b * b * x * x).sum() + 0.1 * (x**3).sum())


def _egrad(x, co):
    if isinstance(x, tuple):
        return tuple(_egrad(xi, ci) for xi, ci in zip(x, co))
    a, b = co
    return a + b * b * x + 0.3 * x * x


def _ehess(x, u, co):
    if isinstance(x, tuple):
        return tuple(_ehess(xi, ui, ci) for xi, ui, ci in zip(x, u, co))
    _, b = co
    return b * b * u + 0.6 * x * u


class TestRandomPoint:
    @PARAMS
    def test_on_manifold(self, m: Manifold):
        x = m.random_point(3, generator=gen())
        assert m.check_point(x) == (True, "")

    @PARAMS
    def test_seeded(self, m: Manifold):
        assert _maxdiff(m.random_point(2, generator=gen(5)), m.random_point(2, generator=gen(5))) == 0.0

    @PARAMS
    def test_dtype(self, m: Manifold):
        x = m.random_point(generator=gen(), dtype=torch.float32)
        assert (x[0] if isinstance(x, tuple) else x).dtype == torch.float32
        assert m.check_point(x)[0]


class TestRetr:
    @PARAMS
    def test_lands_on_manifold(self, m: Manifold):
        x = m.random_point(4, generator=gen(1))
        u = _scale(0.7, m.random_tangent(x, generator=gen(2)))
        assert m.check_point(m.retr(x, u)) == (True, "")
        assert m.check_point(m.expmap(x, u)) == (True, "")

    @PARAMS
    def test_zero(self, m: Manifold):
        x = m.random_point(2, generator=gen(1))
        assert _maxdiff(m.retr(x, m.zero_vector(x)), x) < 1e-12
        assert _maxdiff(m.expmap(x, m.zero_vector(x)), x) < 1e-12

    @PARAMS
    def test_first_order(self, m: Manifold):
        # retr(x, t u) = x + t u + O(t^2)
        x = m.random_point(generator=gen(1))
        u = m.random_tangent(x, generator=gen(2))
        t = 1e-5
        for step in (m.retr, m.expmap):
            assert _maxdiff(_scale(1 / t, _map(lambda a, b: a - b, step(x, _scale(t, u)), x)), u) < 1e-4


class TestProju:
    @PARAMS
    def test_idempotent_and_tangent(self, m: Manifold):
        x = m.random_point(3, generator=gen(1))
        amb = _map(lambda v: torch.randn(v.shape, generator=gen(4), dtype=DT), x)
        u = m.proju(x, amb)
        assert _maxdiff(m.proju(x, u), u) < 1e-12
        assert m.check_vector(x, u) == (True, "")

    @PARAMS
    def test_orthogonal(self, m: Manifold):
        # the removed part is orthogonal to every tangent vector
        x = m.random_point(generator=gen(1))
        amb = _map(lambda v: torch.randn(v.shape, generator=gen(4), dtype=DT), x)
        normal = _map(lambda a, b: a - b, amb, m.proju(x, amb))
        v = m.random_tangent(x, generator=gen(6))
        assert abs(float(m.inner(x, normal, v))) < 1e-12


class TestProjx:
    @PARAMS
    def test_idempotent(self, m: Manifold):
        x = m.random_point(3, generator=gen(1))
        assert _maxdiff(m.projx(x), x) < 1e-10
        noisy = _map(lambda v: v + 0.05 * torch.randn(v.shape, generator=gen(7), dtype=DT), x)
        y = m.projx(noisy)
        assert m.check_point(y) == (True, "")
        assert _maxdiff(m.projx(y), y) < 1e-10


class TestBatch:
    @PARAMS
    def test_batch_equals_loop(self, m: Manifold):
        x = m.random_point(3, generator=gen(1))
        u = m.random_tangent(x, generator=gen(2))
        v = m.random_tangent(x, generator=gen(3))
        co = _coeffs(x)
        g = _egrad(x, co)
        h = _ehess(x, u, co)
        batched = {
            "retr": m.retr(x, u),
            "expmap": m.expmap(x, u),
            "proju": m.proju(x, v),
            "rhess": m.ehess2rhess(x, g, h, u),
            "inner": m.inner(x, u, v),
        }
        for i in range(3):
            xi, ui, vi, gi, hi = (_map(lambda t, i=i: t[i], a) for a in (x, u, v, g, h))
            single = {
                "retr": m.retr(xi, ui),
                "expmap": m.expmap(xi, ui),
                "proju": m.proju(xi, vi),
                "rhess": m.ehess2rhess(xi, gi, hi, ui),
                "inner": m.inner(xi, ui, vi),
            }
            for key, val in single.items():
                assert _maxdiff(_map(lambda t, i=i: t[i], batched[key]), val) < 1e-12, key


class TestDerivatives:
    @PARAMS
    def test_gradient_finite_difference(self, m: Manifold):
        x = m.random_point(generator=gen(11))
        u = m.random_tangent(x, generator=gen(12))
        co = _coeffs(x)
        rgrad = m.egrad2rgrad(x, _egrad(x, co))
        slope = float(m.inner(x, rgrad, u))
        t = 1e-6
        fd = (_cost(m.retr(x, _scale(t, u)), co) - _cost(m.retr(x, _scale(-t, u)), co)) / (2 * t)
        assert abs(fd - slope) < 1e-6 * max(1.0, abs(slope))

    @PARAMS
    def test_hessian_finite_difference(self, m: Manifold):
        # along a geodesic the second-order model's error shrinks like t^3
        x = m.random_point(generator=gen(21))
        u = m.random_tangent(x, generator=gen(22))
        co = _coeffs(x)
        g = _egrad(x, co)
        rgrad = m.egrad2rgrad(x, g)
        hu = m.ehess2rhess(x, g, _ehess(x, u, co), u)
        f0, slope, curv = _cost(x, co), float(m.inner(x, rgrad, u)), float(m.inner(x, hu, u))

        def err(t):
            return abs(_cost(m.expmap(x, _scale(t, u)), co) - f0 - t * slope - 0.5 * t * t * curv)

        e1, e2 = err(1e-2), err(1e-3)
        assert e2 < 1e-9 or math.log10(e1 / e2) > 2.5

    @PARAMS
    def test_hessian_symmetric(self, m: Manifold):
        x = m.random_point(generator=gen(31))
        u = m.random_tangent(x, generator=gen(32))
        v = m.random_tangent(x, generator=gen(33))
        co = _coeffs(x)
        g = _egrad(x, co)
        hu = m.ehess2rhess(x, g, _ehess(x, u, co), u)
        hv = m.ehess2rhess(x, g, _ehess(x, v, co), v)
        assert abs(float(m.inner(x, hu, v)) - float(m.inner(x, u, hv))) < 1e-10
        assert m.check_vector(x, hu) == (True, "")


class TestCheckPoint:
    def test_wrong_shape(self):
        ok, reason = SpecialOrthogonal(3).check_point(torch.eye(2, dtype=DT))
        assert not ok and "expected shape (..., 3, 3)" in reason and "got (2, 2)" in reason

    def test_not_orthogonal(self):
        ok, reason = SpecialOrthogonal(3).check_point(2 * torch.eye(3, dtype=DT))
        assert not ok and "orthogonal" in reason

    def test_reflection(self):
        ok, reason = SpecialOrthogonal(3).check_point(torch.diag(torch.tensor([1.0, 1.0, -1.0], dtype=DT)))
        assert not ok and "determinant" in reason

    def test_plane_outside_block(self):
        m = PlaneRotations(3, (0, 1))
        ok, reason = m.check_point(PlaneRotations(3, (0, 2)).random_point(generator=gen(1)))
        assert not ok and "identity outside the plane" in reason

    def test_nan(self):
        x = torch.eye(3, dtype=DT)
        x[0, 0] = float("nan")
        ok, reason = SpecialOrthogonal(3).check_point(x)
        assert not ok and "finite" in reason

    def test_product_length(self):
        m = ProductManifold(Euclidean(2), Euclidean(3))
        ok, reason = m.check_point((torch.zeros(2, dtype=DT),))
        assert not ok and "tuple of 2 components" in reason

    def test_not_tensor(self):
        ok, reason = Euclidean(2).check_point([0.0, 1.0])
        assert not ok and "expected a tensor" in reason


class TestPlaneRotations:
    def test_angle_roundtrip(self):
        m = PlaneRotations(5, (3, 1))
        angle = torch.tensor([0.3, -2.0, 3.0], dtype=DT)
        assert torch.allclose(m.angle(m.from_angle(angle)), angle)

    def test_retr_adds_angles(self):
        m = PlaneRotations(3, (0, 2))
        x = m.from_angle(torch.tensor(0.4, dtype=DT))
        u = m.proju(x, m.from_angle(torch.tensor(0.4, dtype=DT)) @ torch.tensor([[0, 0, -1.0], [0, 0, 0], [1.0, 0, 0]], dtype=DT))
        assert torch.allclose(m.angle(m.retr(x, 0.5 * u)), torch.tensor(0.9, dtype=DT))


class TestConstructorErrors:
    @pytest.mark.parametrize(
        "make, text",
        [
            (lambda: SpecialOrthogonal(0), "n: expected an integer >= 1"),
            (lambda: SpecialOrthogonal(3, retraction="bogus"), "retraction: expected one of"),
            (lambda: Stiefel(2, 3), "1 <= p <= n"),
            (lambda: PlaneRotations(3, (1, 1)), "plane: expected two different axes"),
            (lambda: PlaneRotations(1), "d: expected an integer >= 2"),
            (lambda: Euclidean(0), "shape: expected positive integers"),
            (lambda: ProductManifold(), "manifolds: expected one or more"),
        ],
    )
    def test_exception(self, make, text):
        with pytest.raises(InputValueError, match=text):
            make()
