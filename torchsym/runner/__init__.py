"""Whole datasets from one config: resumable runs on Dask, and scoring against ground truth.

    summary = torchsym.run("configs/pointcloud_plane.yaml", ["scans/*.ply"], "results.jsonl")
    records = torchsym.read_results("results.jsonl")
    scores = torchsym.evaluate("results.jsonl", truth="planes.jsonl")

:mod:`~torchsym.runner.driver` (the run), :mod:`~torchsym.runner.engine` (serial, local
cluster or remote Dask scheduler), :mod:`~torchsym.runner.store` (the JSON-lines results
file, resume and lock), :mod:`~torchsym.runner.task` (one input on a worker),
:mod:`~torchsym.runner.truth` (ground truth readers), :mod:`~torchsym.runner.scoring`
(scores against it) and
:mod:`~torchsym.runner.cli` (``torchsym run`` and ``torchsym evaluate``).
"""

from typing import TYPE_CHECKING

from torchsym._lazy import lazy_members

_EXPORTS: dict[str, str] = {
    **dict.fromkeys(("EngineOptions", "RunSummary", "expand_inputs", "run"), "torchsym.runner.driver"),
    "EngineError": "torchsym.runner.engine",
    **dict.fromkeys(("Evaluation", "evaluate", "format_evaluation"), "torchsym.runner.scoring"),
    **dict.fromkeys(("GroundTruth", "read_truth"), "torchsym.runner.truth"),
    **dict.fromkeys(("ResultsStore", "read_results"), "torchsym.runner.store"),
}

__all__ = [
    "EngineError",
    "EngineOptions",
    "Evaluation",
    "GroundTruth",
    "ResultsStore",
    "RunSummary",
    "evaluate",
    "expand_inputs",
    "format_evaluation",
    "read_results",
    "read_truth",
    "run",
]

__getattr__, __dir__ = lazy_members(__name__, _EXPORTS, globals())

if TYPE_CHECKING:
    from torchsym.runner.driver import EngineOptions, RunSummary, expand_inputs, run
    from torchsym.runner.engine import EngineError
    from torchsym.runner.scoring import Evaluation, evaluate, format_evaluation
    from torchsym.runner.truth import GroundTruth, read_truth
    from torchsym.runner.store import ResultsStore, read_results
