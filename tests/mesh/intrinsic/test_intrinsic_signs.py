"""The sign hypotheses of the first eigenfunctions (``hypotheses.sign_basis``), the choice of a
reflection among the hypotheses and the result's score."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from torchsym.errors import ConfigError
from torchsym.mesh import intrinsic_symmetry
from torchsym.mesh.synthetic import twist
from torchsym.metrics.mesh import correspondence_rate


def test_cardinality_and_values(monkeypatch, blob):
    from torchsym.mesh.intrinsic import hypotheses, solver

    seen = {}
    original = hypotheses.sign_basis_candidates

    def spy(ws, m, pairs):
        seen["out"], seen["k"] = original(ws, m, pairs), ws.plan.n_eigen
        return seen["out"]

    monkeypatch.setattr(solver, "sign_basis_candidates", spy)
    intrinsic_symmetry(blob[0], hypotheses={"sign_basis": 4, "sign_basis_below": 2.0})  # always added
    out, k = seen["out"], seen["k"]
    assert len(out) == 2**3 - 1
    diagonals = {tuple(np.diag(c.fmap)) for c in out}
    assert len(diagonals) == 7  # every sign vector once
    for c in out:
        d = np.diag(c.fmap)
        assert c.name == "signs" and c.fmap.shape == (k, k) and d[0] == 1.0 and (d[4:] == 1.0).all()
        assert (d[1:4] < 0).any()  # never the identity
        assert c.query.shape[1] == 4 and np.allclose(c.target, c.query * d[:4])


def test_only_where_the_score_is_low(monkeypatch, blob):
    """The sign hypotheses are added only when no other hypothesis passes step 9 as a reflection
    scoring ``hypotheses.sign_basis_below``; the blob's mirror does."""
    from torchsym.mesh.intrinsic import solver

    calls = []
    original = solver.sign_basis_candidates

    def spy(ws, m, pairs):
        calls.append(m)
        return original(ws, m, pairs)

    monkeypatch.setattr(solver, "sign_basis_candidates", spy)
    skipped = intrinsic_symmetry(blob[0])
    assert not calls and skipped.score >= 0.8
    always = intrinsic_symmetry(blob[0], hypotheses={"sign_basis_below": 2.0})
    assert calls == [4] and torch.equal(always.map, skipped.map)


def test_exception(blob):
    with pytest.raises(ConfigError, match="hypotheses.sign_basis"):
        intrinsic_symmetry(blob[0], hypotheses={"sign_basis": 9})
    with pytest.raises(ConfigError, match="select.weak_score"):
        intrinsic_symmetry(blob[0], select={"weak_score": 1.5})


def test_score_separates_the_mirror_from_a_wrong_map(blob):
    mesh, gt = blob
    bent = twist(mesh, angle=0.3)
    out = intrinsic_symmetry(bent)
    assert correspondence_rate(bent, out.map, ground_truth=torch.from_numpy(gt)).rate > 0.95
    assert 0.6 < out.score <= 1.0
    assert not any("weak" in n for n in out.notes)
    # the thesis's map alone, unrefined, on a shape without pairs is no reflection: low score and a note
    ident = intrinsic_symmetry(bent, hypotheses={"sign_basis": 0, "hks_pairs": False, "orientation": False},
                               pairs={"max_cost": 1e-9}, extrinsic={"enabled": False})
    assert 0.0 <= ident.score < 0.5
    assert any("weak" in n for n in ident.notes)


def test_score_in_result_dict(solved):
    out, _, _ = solved
    d = out.to_dict()
    assert 0.0 <= d["score"] <= 1.0
