"""Writing a benchmark's report: the Markdown table printed and saved beside its JSON."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any


def write_report(folder: str | Path, stem: str, text: str, data: Any) -> None:
    """Print ``text`` and write it to ``folder/stem.md``, ``data`` to ``folder/stem.json``."""
    print(text)
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{stem}.md").write_text(text)
    (out / f"{stem}.json").write_text(json.dumps(data, indent=2))
