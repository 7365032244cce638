"""The records steps hand on (frozen: a step returns a new one) and the stopwatch of the steps."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from torchsym.mesh.intrinsic import solver
from torchsym.mesh.intrinsic.workspace import Candidate, Stopwatch, Workspace


def test_smoke_stopwatch():
    watch = Stopwatch()
    with watch("select"):
        pass
    watch.add("select", 1.0)
    watch.add_all({"pairs": 0.5, "select": 0.25})
    out = watch.as_dict()
    assert set(out) == {"select", "pairs"} and out["pairs"] == 0.5 and 1.25 <= out["select"] < 1.3


def test_frozen(blob, monkeypatch):
    seen = {}
    original = solver.choose

    def spy(ws, candidates, images):
        seen["ws"], seen["in"] = ws, list(candidates)
        seen["out"] = original(ws, candidates, images)
        return seen["out"]

    monkeypatch.setattr(solver, "choose", spy)
    solver.intrinsic_symmetry(blob[0])
    ws, before, (after, table, best, _) = seen["ws"], seen["in"], seen["out"]
    assert isinstance(ws, Workspace) and ws.probe is not None
    with pytest.raises(dataclasses.FrozenInstanceError):
        ws.probe = None
    with pytest.raises(dataclasses.FrozenInstanceError):
        before[0].refined = np.eye(3)
    # step 9 returns its findings in new records and leaves the hypotheses it was given as they were
    assert all(isinstance(c, Candidate) and c.refined is None and c.start is None for c in before)
    assert len(after) == len(before) == table.shape[0] and after[best].refined is not None
    assert all(a.name == b.name and a.fmap is b.fmap for a, b in zip(after, before))
