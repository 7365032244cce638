"""run_branches: results in the order given, errors raised, a serial path."""

import threading
import time

import pytest

from torchsym.core.parallel import run_branches


def test_results_keep_the_order_given_whatever_finishes_first():
    def task(i, delay):
        def run():
            time.sleep(delay)
            return i, threading.get_ident()

        return run

    out = run_branches([task(0, 0.05), task(1, 0.0), task(2, 0.02)], max_workers=2)
    assert [i for i, _ in out] == [0, 1, 2]


def test_branches_run_on_more_than_one_thread():
    barrier = threading.Barrier(2, timeout=5)  # both tasks must be running at once to pass

    def task():
        barrier.wait()
        return threading.get_ident()

    first, second = run_branches([task, task], max_workers=2)
    assert first != second


def test_one_worker_runs_on_the_calling_thread():
    out = run_branches([threading.get_ident, threading.get_ident], max_workers=1)
    assert out == [threading.get_ident()] * 2


def test_the_first_error_in_the_order_given_is_raised_after_every_task_ended():
    done = []

    def fails(exc):
        def run():
            raise exc

        return run

    def slow():
        time.sleep(0.05)
        done.append(True)

    with pytest.raises(KeyError):
        run_branches([slow, fails(KeyError("a")), fails(ValueError("b"))], max_workers=3)
    assert done == [True]


def test_no_tasks():
    assert run_branches([]) == []


def test_torch_threads_bound_the_branches_and_kd_tree_queries():
    import torch

    from torchsym.core.parallel import thread_budget
    from torchsym.matching.knn import KNNIndex

    before = torch.get_num_threads()
    try:
        torch.set_num_threads(1)
        assert thread_budget() == 1
        out = run_branches([threading.get_ident, threading.get_ident])  # default: the budget
        assert out == [threading.get_ident()] * 2
        pts = torch.randn(30000, 3, generator=torch.Generator().manual_seed(0))
        d1, i1 = KNNIndex(pts).query(pts + 0.01)
        torch.set_num_threads(2)
        assert thread_budget() == 2
        d2, i2 = KNNIndex(pts).query(pts + 0.01)
        assert torch.equal(i1, i2) and torch.equal(d1, d2)
    finally:
        torch.set_num_threads(before)
