"""One static page to review a whole run: ``<figures>/index.html``.

One row per input (the latest record of each): a thumbnail of its first picture, the
input's name, status, score, seconds, the error message of a failure, and links to its
pictures and to its record as JSON (``records/<stem>.json``, written beside the page). The
table sorts by any column when its header is clicked (a few lines of inline JavaScript);
the page needs no server and no network: open it from disk. Every text taken from an input
is escaped, so a file named ``<b>x</b>.png`` shows as text.
"""

from __future__ import annotations

import html
import json
import math
import os
import re
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any
from urllib.parse import quote

from torchsym.io.inputs import unique_stems

__all__ = ["record_score", "write_index"]

_STYLE = """
body{font-family:system-ui,sans-serif;margin:1.2em;color:#222}
table{border-collapse:collapse;width:100%}
th,td{border-bottom:1px solid #ddd;padding:4px 8px;text-align:left;vertical-align:middle}
th{background:#f3f3f3;cursor:pointer;user-select:none;position:sticky;top:0}
th.sorted-asc::after{content:" \\25B2"}th.sorted-desc::after{content:" \\25BC"}
td.num{text-align:right;font-variant-numeric:tabular-nums}
img.thumb{max-width:240px;max-height:150px;display:block}
.ok{color:#1a7f37}.error{color:#b42318}.crashed{color:#b42318;font-weight:bold}
.msg{font-family:monospace;font-size:85%;max-width:40em;white-space:pre-wrap;overflow-wrap:anywhere}
.msg:not(:empty){min-width:22em}
.links{font-size:85%}.links a{display:block;white-space:nowrap}
"""

# sorts the table by a clicked column: numbers by data-sort, missing values last
_SCRIPT = """
document.querySelectorAll('th[data-col]').forEach(function(th){th.addEventListener('click',function(){
 var col=+th.dataset.col,num=th.dataset.num==='1',body=document.querySelector('tbody');
 var desc=!th.classList.contains('sorted-desc');
 document.querySelectorAll('th').forEach(function(h){h.classList.remove('sorted-asc','sorted-desc')});
 th.classList.add(desc?'sorted-desc':'sorted-asc');
 var rows=Array.prototype.slice.call(body.rows);
 rows.sort(function(a,b){var x=a.cells[col].dataset.sort,y=b.cells[col].dataset.sort;
  if(x===''&&y==='')return 0;if(x==='')return 1;if(y==='')return -1;
  var c=num?(+x)-(+y):x.localeCompare(y,undefined,{numeric:true});return desc?-c:c;});
 rows.forEach(function(r){body.appendChild(r)});});});
"""


def record_score(result: Any) -> float | None:
    """The score of a result as recorded (its ``to_dict()``): ``score``, else the best of
    ``scores``; None when it has neither or no axis was found."""
    if not isinstance(result, Mapping):
        return None
    for name in ("score", "scores"):
        value = result.get(name)
        if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
            return float(value)
        if isinstance(value, list):
            flat = [float(x) for x in value if isinstance(x, (int, float)) and math.isfinite(x)]
            if flat:
                return max(flat)
            return None
    return None


def _natural(text: str) -> list[Any]:
    """Sort key that orders numbers in names by value (``human_2`` before ``human_10``)."""
    return [(0, int(part), "") if part.isdigit() else (1, 0, part.lower()) for part in re.split(r"(\d+)", text) if part]


def _href(target: Path, root: Path) -> str:
    """Escaped relative URL of ``target`` from the page in ``root``."""
    return html.escape(quote(os.path.relpath(target, root).replace(os.sep, "/")), quote=True)


def _error_text(rec: Mapping[str, Any]) -> str:
    err = rec.get("error")
    if isinstance(err, Mapping):
        return f"{err.get('type') or 'error'}: {err.get('message') or ''}".strip()
    if err:
        return str(err)
    if rec.get("status") == "crashed":
        return f"the worker died on every attempt ({rec.get('attempts') or '?'})"
    return ""


def _row(rec: Mapping[str, Any], stem: str, root: Path, json_path: Path) -> str:
    esc = html.escape
    name = Path(str(rec.get("input"))).name
    status = str(rec.get("status") or "unknown")
    score = record_score(rec.get("result")) if status == "ok" else None
    seconds = rec.get("seconds")
    seconds = float(seconds) if isinstance(seconds, (int, float)) and not isinstance(seconds, bool) else None
    pictures = [Path(a) for a in rec.get("artifacts") or [] if Path(a).is_file()]
    pngs = [p for p in pictures if p.suffix.lower() == ".png"]
    thumb = f'<a href="{_href(pngs[0], root)}"><img class="thumb" loading="lazy" src="{_href(pngs[0], root)}" alt="{esc(pngs[0].name)}"></a>' if pngs else ""
    links = "".join(f'<a href="{_href(p, root)}">{esc(p.name)}</a>' for p in pictures)
    links += f'<a href="{_href(json_path, root)}">record (JSON)</a>'
    cells = [
        f"<td>{thumb}</td>",
        f'<td data-sort="{esc(name)}" title="{esc(str(rec.get("input")))}">{esc(name)}</td>',
        f'<td data-sort="{esc(status)}" class="{esc(status)}">{esc(status)}</td>',
        f'<td class="num" data-sort="{"" if score is None else f"{score:.6g}"}">{"" if score is None else f"{score:.3f}"}</td>',
        f'<td class="num" data-sort="{"" if seconds is None else f"{seconds:.6g}"}">{"" if seconds is None else f"{seconds:.2f}"}</td>',
        f'<td class="msg" data-sort="{esc(_error_text(rec))}">{esc(_error_text(rec))}</td>',
        f'<td class="links">{links}</td>',
    ]
    return f'<tr id="{esc(stem)}">' + "".join(cells) + "</tr>"


def write_index(records: Sequence[Mapping[str, Any]], figures_dir: str | Path, *, results: str | Path | None = None, title: str = "") -> Path:
    """Write ``figures_dir/index.html`` and ``figures_dir/records/<stem>.json`` (replacing both).

    Args:
        records: one record per input, as :func:`torchsym.runner.store.read_results` gives
            them (``input``, ``status``, ``result``, ``error``, ``seconds``, ``artifacts``).
        figures_dir: the run's picture folder (created if missing); pictures are linked
            relative to it, so the folder can be moved whole.
        results: the run's results file, linked from the page's header.
        title: the page's heading (default: the results file's name).

    Returns:
        The page's path.
    """
    root = Path(figures_dir)
    (root / "records").mkdir(parents=True, exist_ok=True)
    records = sorted(records, key=lambda r: (_natural(Path(str(r.get("input"))).name), _natural(str(r.get("input")))))
    inputs = [str(r.get("input")) for r in records]
    rows = []
    for rec, stem in zip(records, unique_stems([Path(p) for p in inputs])):
        json_path = root / "records" / f"{stem}.json"
        json_path.write_text(json.dumps(rec, indent=1, default=str))
        rows.append(_row(rec, stem, root, json_path))
    counts = Counter(str(r.get("status")) for r in records)
    esc = html.escape
    heading = title or (f"run: {Path(results).name}" if results is not None else "run")
    summary = f"{len(records)} inputs: " + ", ".join(f"{counts[s]} {s}" for s in sorted(counts)) if records else "no inputs recorded"
    if results is not None and Path(results).is_file():
        summary += f' &middot; results file: <a href="{_href(Path(results), root)}">{esc(Path(results).name)}</a>'
    head = "".join(
        f'<th data-col="{i}" data-num="{int(num)}">{label}</th>' if sortable else f"<th>{label}</th>"
        for i, (label, sortable, num) in enumerate(
            [("picture", False, False), ("input", True, False), ("status", True, False), ("score", True, True),
             ("seconds", True, True), ("error", True, False), ("files", False, False)]
        )
    )
    page = (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{esc(heading)}</title><style>{_STYLE}</style></head><body>\n"
        f"<h1>{esc(heading)}</h1>\n<p>{summary}. Click a column's header to sort by it.</p>\n"
        f"<table><thead><tr>{head}</tr></thead><tbody>\n" + "\n".join(rows) + "\n</tbody></table>\n"
        f"<script>{_SCRIPT}</script></body></html>\n"
    )
    path = root / "index.html"
    tmp = root / ".index.html.tmp"
    tmp.write_text(page, encoding="utf-8")
    os.replace(tmp, path)
    return path
