from pathlib import Path

import torchsym  # noqa: F401
from torchsym.core.glossary import MARKER, settings_tables, shared_name_units

GLOSSARY = Path(__file__).resolve().parents[2] / "docs" / "glossary.md"


def test_glossary_is_current():
    text = GLOSSARY.read_text()
    assert MARKER in text, "docs/glossary.md lacks its generated part: run python scripts/glossary.py"
    assert text.split(MARKER, 1)[1].strip() == settings_tables().split(MARKER, 1)[1].strip(), (
        "docs/glossary.md is out of date: run python scripts/glossary.py"
    )


def test_one_unit_per_name():
    clashes = {name: units for name, units in shared_name_units().items() if len(units) > 1}
    assert not clashes, f"settings sharing a name with different units: {clashes}"
