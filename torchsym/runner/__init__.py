"""Whole datasets from one config: resumable runs on Dask, and scoring against ground truth.

    summary = torchsym.run("configs/pointcloud_plane.yaml", ["scans/*.ply"], "results.jsonl")
    records = torchsym.read_results("results.jsonl")
    scores = torchsym.evaluate("results.jsonl", truth="planes.jsonl")

:mod:`~torchsym.runner.driver` (the run), :mod:`~torchsym.runner.engine` (serial, local
cluster or remote Dask scheduler), :mod:`~torchsym.runner.store` (the JSON-lines results
file, resume and lock), :mod:`~torchsym.runner.task` (one input on a worker),
:mod:`~torchsym.runner.evaluate` (ground truth readers and scores) and
:mod:`~torchsym.runner.cli` (``torchsym run`` and ``torchsym evaluate``).
"""

from torchsym.runner.driver import RunSummary, expand_inputs, run
from torchsym.runner.engine import EngineError
from torchsym.runner.evaluate import Evaluation, GroundTruth, evaluate, format_evaluation, read_truth
from torchsym.runner.store import ResultsStore, read_results

__all__ = [
    "EngineError",
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
