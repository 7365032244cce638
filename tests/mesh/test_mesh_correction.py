from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.errors import InputShapeError
from torchsym.mesh import correct_eigenfunctions, correction_cost
from torchsym.mesh import correction as correction_module


def _problem(seed=0, k=5, m=6):
    rng = np.random.default_rng(seed)
    evals = np.sort(rng.random(k))
    fb, gb = rng.standard_normal((k, m)), rng.standard_normal((k, m))
    signs = np.array([1.0, -1.0, 0.0, 1.0, -1.0])[:k]
    return evals, fb, gb, signs


class TestCorrectEigenfunctions:
    def test_derivatives_match_autograd(self, monkeypatch):
        evals, fb, gb, signs = _problem()
        seen = {}

        def capture(manifold, cost, x0, *, egrad, ehess, **kw):
            seen.update(cost=cost, egrad=egrad, ehess=ehess)
            raise RuntimeError("captured")

        monkeypatch.setattr(correction_module, "trust_region", capture)
        with pytest.raises(RuntimeError, match="captured"):
            correct_eigenfunctions(evals, fb, gb, signs, mu=0.7)
        rng = np.random.default_rng(1)
        r = torch.linalg.qr(torch.tensor(rng.standard_normal((5, 5))))[0].requires_grad_(True)
        u = torch.tensor(rng.standard_normal((5, 5)))
        (g,) = torch.autograd.grad(seen["cost"](r), r, create_graph=True)
        (hu,) = torch.autograd.grad((g * u).sum(), r)
        torch.testing.assert_close(seen["egrad"](r.detach()), g.detach())
        torch.testing.assert_close(seen["ehess"](r.detach(), u), hu)

    def test_gradcheck(self):
        evals, fb, gb, _ = _problem(k=3, m=2)
        e, f, g = torch.tensor(evals), torch.tensor(fb), torch.tensor(gb)
        s = torch.tensor([1.0, -1.0, 1.0], dtype=torch.float64)
        r = torch.linalg.qr(torch.tensor(np.random.default_rng(4).standard_normal((3, 3))))[0].requires_grad_(True)
        assert torch.autograd.gradcheck(lambda x: correction_cost(x, e, f, g, s, 0.5), (r,))

    def test_decreases_and_rotation(self):
        evals, fb, gb, signs = _problem(2)
        res = correct_eigenfunctions(evals, fb, gb, signs, mu=1.0, max_iter=100)
        r = res.rotation
        assert res.cost <= res.cost_before
        torch.testing.assert_close(r.T @ r, torch.eye(5, dtype=torch.float64), atol=1e-10, rtol=0)
        assert float(torch.linalg.det(r)) == pytest.approx(1.0)

    def test_planted_mixing(self):
        # two equal eigenvalues whose basis is rotated by 0.4 rad away from the even/odd pair
        evals = np.array([0.0, 0.5, 0.5, 1.0])
        rng = np.random.default_rng(3)
        true_coef = rng.standard_normal((4, 8))  # coefficients in the clean basis
        signs = np.array([1.0, 1.0, -1.0, 1.0])
        c, s = np.cos(0.4), np.sin(0.4)
        mix = np.eye(4)
        mix[1:3, 1:3] = [[c, -s], [s, c]]  # observed basis = clean basis @ mix
        fb = mix.T @ true_coef
        gb = mix.T @ (signs[:, None] * true_coef)
        res = correct_eigenfunctions(evals, fb, gb, signs, mu=1.0, max_iter=200)
        rot = res.rotation.numpy()
        e = rot.T @ fb - signs[:, None] * (rot.T @ gb)
        assert np.abs(e).max() < 1e-5 and res.converged

    def test_exception(self):
        with pytest.raises(InputShapeError, match=r"fb, gb: expected equal shapes \(k, m\) with k = 3"):
            correct_eigenfunctions(np.ones(3), np.ones((3, 2)), np.ones((3, 4)), np.ones(3))
