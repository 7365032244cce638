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
    calls = []
    original = solver.screen_and_refine

    def spy(ws, candidates, images, seen):
        calls.append((ws, list(candidates), original(ws, candidates, images, seen)))
        return calls[-1][2]

    monkeypatch.setattr(solver, "screen_and_refine", spy)
    solver.intrinsic_symmetry(blob[0])
    ws, before, (after, table, seen) = calls[0]
    assert isinstance(ws, Workspace) and ws.probe is not None
    with pytest.raises(dataclasses.FrozenInstanceError):
        ws.probe = None
    with pytest.raises(dataclasses.FrozenInstanceError):
        before[0].refined = np.eye(3)
    # step 9 returns its findings in new records and leaves the hypotheses it was given as they were
    assert all(isinstance(c, Candidate) and c.refined is None and c.start is None for c in before)
    assert len(after) == len(before) == table.shape[0] == len(seen) and any(c.refined is not None for c in after)
    assert all(a.name == b.name and a.fmap is b.fmap for a, b in zip(after, before))
