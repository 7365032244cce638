"""docs/design/shape.md's layout and sizes are generated from the package and kept current."""

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _script():
    spec = importlib.util.spec_from_file_location("shape_map", ROOT / "scripts" / "shape_map.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_shape_map_is_current():
    script = _script()
    assert script.current() == script.generated(), "docs/design/shape.md is out of date: run python scripts/shape_map.py"


def test_every_module_is_on_the_map():
    script = _script()
    text = script.layout()
    for path in (ROOT / "torchsym").rglob("*.py"):
        if path.stem != "__init__" and "__pycache__" not in path.parts:
            assert f" {path.stem}" in text or f"{path.stem} " in text, f"{path} missing from the map"
