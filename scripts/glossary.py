"""Write the generated part of docs/glossary.md: every solver's settings with their units.

Usage: python scripts/glossary.py
"""

from __future__ import annotations

from pathlib import Path

import torchsym  # noqa: F401  (registers every solver)
from torchsym.core.glossary import MARKER, settings_tables

PATH = Path(__file__).resolve().parents[1] / "docs" / "glossary.md"


def main() -> None:
    text = PATH.read_text()
    head = text.split(MARKER)[0].rstrip() + "\n\n"
    PATH.write_text(head + settings_tables() + "\n")
    print(f"wrote {PATH}")


if __name__ == "__main__":
    main()
