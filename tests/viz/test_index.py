"""The run page: one row per record, every link resolves, names escaped, rewritten on resume."""

from __future__ import annotations

from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlparse

import numpy as np
import pytest

import torchsym
from torchsym.runner import read_results, run
from torchsym.viz.index import record_score, write_index

NASTY = '<b>x</b>&"q\'.xyz'.replace("/", "")  # a file name cannot hold "/"


class _Page(HTMLParser):
    """Rows (their ``id`` and cell texts), every ``href``/``src``, and every tag seen."""

    def __init__(self) -> None:
        super().__init__()
        self.rows: list[dict] = []
        self.links: list[str] = []
        self.tags: list[str] = []
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.append(tag)
        if tag == "tr" and "id" in a:
            self.rows.append({"id": a["id"], "cells": []})
        if tag == "td" and self.rows:
            self._cell = []
        for key in ("href", "src"):
            if key in a:
                self.links.append(a[key])

    def handle_endtag(self, tag):
        if tag == "td" and self._cell is not None:
            self.rows[-1]["cells"].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def _parse(path: Path) -> _Page:
    page = _Page()
    page.feed(path.read_text(encoding="utf-8"))
    return page


def _assert_links_resolve(page: _Page, root: Path) -> None:
    assert page.links
    for link in page.links:
        url = urlparse(link)
        assert not url.scheme and not url.netloc, link  # nothing from the network
        assert (root / unquote(url.path)).is_file(), link


def _records(tmp_path: Path) -> list[dict]:
    fig = tmp_path / "fig"
    fig.mkdir()
    png = fig / "a_axes.png"
    png.write_bytes(b"\x89PNG\r\n\x1a\n")
    nasty_png = fig / (Path(NASTY).stem + "_plane.png")
    nasty_png.write_bytes(b"\x89PNG\r\n\x1a\n")
    return [
        {"input": "/data/a.jpg", "status": "ok", "result": {"scores": [0.2, 0.7]}, "seconds": 1.5, "artifacts": [str(png)]},
        {"input": f"/data/{NASTY}", "status": "ok", "result": {"score": 0.9}, "seconds": 0.25, "artifacts": [str(nasty_png)]},
        {"input": "/data/b.jpg", "status": "error", "result": None, "seconds": 0.1,
         "error": {"type": "InputFileError", "message": "inputs: cannot read '<b.jpg>'"}, "artifacts": []},
        {"input": "/other/a.jpg", "status": "crashed", "result": None, "seconds": None, "error": None, "attempts": 3},
        {"input": "/data/c.jpg", "status": "ok", "result": {"scores": []}, "seconds": 0.3, "artifacts": [str(fig / "gone.png")]},
    ]


class TestRecordScore:
    def test_values(self):
        assert record_score({"score": 0.5}) == 0.5
        assert record_score({"scores": [0.1, 0.4]}) == 0.4
        assert record_score({"scores": []}) is None  # no axis found
        assert record_score({"score": float("nan")}) is None
        assert record_score({"map": [1, 0]}) is None
        assert record_score(None) is None


class TestWriteIndex:
    def test_rows_links_and_escaping(self, tmp_path):
        records = _records(tmp_path)
        path = write_index(records, tmp_path / "fig", results=None)
        assert path == tmp_path / "fig" / "index.html"
        page = _parse(path)
        assert len(page.rows) == len(records)
        names = [r["cells"][1] for r in page.rows]
        assert names == [NASTY, "a.jpg", "a.jpg", "b.jpg", "c.jpg"]  # the nasty name as text; by name, then path
        assert "b" not in page.tags and "i" not in page.tags  # no markup from a name
        assert len({r["id"] for r in page.rows}) == len(records)  # two a.jpg: distinct stems
        _assert_links_resolve(page, tmp_path / "fig")
        by_name = {r["cells"][1]: r["cells"] for r in page.rows[2:] + page.rows[:1]}
        assert by_name[NASTY][2:5] == ["ok", "0.900", "0.25"]
        assert by_name["b.jpg"][2] == "error" and "cannot read '<b.jpg>'" in by_name["b.jpg"][5]
        assert page.rows[1]["cells"][3] == "0.700"  # the best axis
        assert "died" in page.rows[2]["cells"][5]
        assert page.rows[4]["cells"][3] == ""  # no axis: no score
        assert "gone.png" not in path.read_text()  # a missing picture is not linked

    def test_names_sort_naturally(self, tmp_path):
        records = [{"input": f"/m/human_{i}.off", "status": "ok", "result": {"score": 0.5}, "seconds": 1.0}
                   for i in (10, 2, 1)]
        page = _parse(write_index(records, tmp_path / "fig"))
        assert [r["cells"][1] for r in page.rows] == ["human_1.off", "human_2.off", "human_10.off"]
        assert "numeric:true" in (tmp_path / "fig" / "index.html").read_text()  # and so does a click

    def test_static(self, tmp_path):
        html = write_index(_records(tmp_path), tmp_path / "fig").read_text()
        assert "http://" not in html and "https://" not in html
        assert "<script src" not in html and "<link" not in html
        assert "data-num=\"1\"" in html  # the score column sorts numerically

    def test_empty(self, tmp_path):
        page = _parse(write_index([], tmp_path / "fig"))
        assert page.rows == []


class TestRunWritesIndex:
    def test_run_and_resume(self, tmp_path):
        cloud = torchsym.pointcloud.planted_symmetric_cloud(300, generator=0)
        inputs = tmp_path / "in"
        inputs.mkdir()
        good = inputs / NASTY
        np.savetxt(good, cloud.points.numpy())
        bad = inputs / "bad.xyz"
        bad.write_text("not a point cloud\n")
        cfg = {"input": "pointcloud", "steps": [{"name": "reflection_plane", "params": {"n_starts": 2, "seed": 0}}]}
        out, fig = tmp_path / "r.jsonl", tmp_path / "fig"
        run(cfg, [str(good), str(bad)], out, engine="serial", figures=fig)
        page = _parse(fig / "index.html")
        assert sorted(r["cells"][1] for r in page.rows) == sorted([NASTY, "bad.xyz"])
        _assert_links_resolve(page, fig)
        statuses = {r["cells"][1]: r["cells"][2] for r in page.rows}
        assert statuses == {NASTY: "ok", "bad.xyz": "error"}
        # a resumed run with one more input rewrites the page with every record
        more = inputs / "more.xyz"
        np.savetxt(more, cloud.points.numpy() + 1.0)
        summary = run(cfg, [str(good), str(bad), str(more)], out, engine="serial", figures=fig)
        assert summary.n_skipped == 2
        page = _parse(fig / "index.html")
        assert sorted(r["cells"][1] for r in page.rows) == sorted([NASTY, "bad.xyz", "more.xyz"])
        assert len(read_results(out)) == 3
        _assert_links_resolve(page, fig)


@pytest.mark.parametrize("n", [0, 1])
def test_few_records(tmp_path, n):
    records = _records(tmp_path)[:n]
    assert len(_parse(write_index(records, tmp_path / "fig")).rows) == n
