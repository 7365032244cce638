import json
import os

import pytest

from torchsym.errors import InputFileError
from torchsym.runner.store import ResultsStore, config_hash, input_key, read_results


def _rec(name, status="ok", **extra):
    return {"input": name, "size": 1, "mtime_ns": 2, "config_hash": "h", "status": status, "result": {"x": 1.0}, **extra}


class TestResultsStore:
    def test_smoke(self, tmp_path):
        out = tmp_path / "sub" / "r.jsonl"
        with ResultsStore(out) as store:
            store.append(_rec("a"))
            store.append(_rec("b", status="error"))
        lines = out.read_text().splitlines()
        assert [json.loads(line)["input"] for line in lines] == ["a", "b"]
        assert [r["status"] for r in read_results(out)] == ["ok", "error"]

    def test_latest_record_wins(self, tmp_path):
        out = tmp_path / "r.jsonl"
        with ResultsStore(out) as store:
            store.append(_rec("a", status="crashed"))
            store.append(_rec("b"))
            store.append(_rec("a"))
        assert [(r["input"], r["status"]) for r in read_results(out)] == [("a", "ok"), ("b", "ok")]
        assert len(read_results(out, latest=False)) == 3

    def test_keeps_no_results_in_memory(self, tmp_path):
        # a long run's records can hold per-point arrays: the store keeps keys and statuses only
        out = tmp_path / "r.jsonl"
        with ResultsStore(out) as store:
            store.append(_rec("a", attempts=2))
            assert store.latest("a") == {"input": "a", "size": 1, "mtime_ns": 2, "config_hash": "h", "status": "ok", "attempts": 2}
        with ResultsStore(out) as store:  # the same when reopened
            assert "result" not in store.latest("a") and store.latest("a")["attempts"] == 2
        assert read_results(out)[0]["result"] == {"x": 1.0}

    def test_nan_written_as_null(self, tmp_path):
        out = tmp_path / "r.jsonl"
        with ResultsStore(out) as store:
            store.append(_rec("a", seconds=float("nan")))
        assert read_results(out)[0]["seconds"] is None

    def test_torn_last_line(self, tmp_path):
        out = tmp_path / "r.jsonl"
        good = json.dumps(_rec("a")) + "\n" + json.dumps(_rec("b")) + "\n"
        out.write_text(good + json.dumps(_rec("c"))[:25])
        assert [r["input"] for r in read_results(out)] == ["a", "b"]  # reading leaves the file alone
        assert out.stat().st_size > len(good)
        with ResultsStore(out) as store:
            assert store.torn_bytes == 25
            assert store.latest("c") is None and store.latest("b")["status"] == "ok"
            store.append(_rec("c"))
        assert [r["input"] for r in read_results(out)] == ["a", "b", "c"]
        assert out.read_text().startswith(good)

    def test_complete_last_line_without_newline_is_torn(self, tmp_path):
        out = tmp_path / "r.jsonl"
        out.write_text(json.dumps(_rec("a")) + "\n" + json.dumps(_rec("b")))
        with ResultsStore(out) as store:
            assert store.latest("b") is None
        assert out.read_text().endswith("\n")

    def test_lock(self, tmp_path):
        out = tmp_path / "r.jsonl"
        with ResultsStore(out):
            with pytest.raises(InputFileError, match=rf"is locked by another torchsym run \(pid {os.getpid()}\)"):
                ResultsStore(out).open()
        with ResultsStore(out) as store:  # released on close
            store.append(_rec("a"))

    def test_exception(self, tmp_path):
        out = tmp_path / "r.jsonl"
        out.write_text(json.dumps(_rec("a")) + "\nnot json\n" + json.dumps(_rec("b")) + "\n")
        with pytest.raises(InputFileError, match="line 2 of .* is not a JSON record"):
            ResultsStore(out).open()
        with pytest.raises(InputFileError, match="does not exist"):
            read_results(tmp_path / "missing.jsonl")

    def test_no_resume_starts_afresh(self, tmp_path):
        out = tmp_path / "r.jsonl"
        out.write_text(json.dumps(_rec("a")) + "\n")
        with ResultsStore(out, resume=False) as store:
            assert store.latest("a") is None
            store.append(_rec("b"))
        assert [r["input"] for r in read_results(out)] == ["b"]


class TestInputKey:
    def test_is_done(self, tmp_path):
        f = tmp_path / "x.xyz"
        f.write_text("0 0 0\n")
        key = input_key(f, "h1")
        out = tmp_path / "r.jsonl"
        with ResultsStore(out) as store:
            assert not store.is_done(key)
            store.append({**key.as_dict(), "status": "crashed"})
            assert not store.is_done(key)  # crashed items run again
            store.append({**key.as_dict(), "status": "error"})
            assert store.is_done(key)
            assert not store.is_done(input_key(f, "h2"))  # another config
            os.utime(f, ns=(1, 1))
            assert not store.is_done(input_key(f, "h1"))  # the file changed

    def test_config_hash(self):
        a = {"input": "pointcloud", "steps": [{"name": "s", "params": {"a": 1, "b": 2}}], "description": "x"}
        b = {"description": "y", "steps": [{"params": {"b": 2, "a": 1}, "name": "s"}], "input": "pointcloud"}
        assert config_hash(a) == config_hash(b)
        assert config_hash(a) != config_hash({**a, "steps": [{"name": "s", "params": {"a": 2, "b": 2}}]})
