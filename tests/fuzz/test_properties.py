"""The fuzz properties (``fuzz_properties.py``) under a short seeded profile: each entry
point added since ``tests/test_fuzz.py`` ends with a result or a typed error, finite
where due, inputs untouched, same seed same bits. ``scripts/fuzz.py`` runs the long
campaign (one example per process, with time and memory limits)."""

import pytest
from hypothesis import HealthCheck, settings

from fuzz_properties import PROPERTIES

# examples per property in CI: the slower entry points (whole solvers) get fewer
EXAMPLES = {"detector_settings": 16, "symmetry_map": 12, "stylize": 8, "symm_slic": 12, "multiview_detect": 0, "run_options": 8, "evaluate": 25}


@pytest.mark.parametrize("name", [n for n in PROPERTIES if EXAMPLES.get(n, 30)])
def test_property(name):
    profile = settings(max_examples=EXAMPLES.get(name, 30), derandomize=True, deadline=None, database=None,
                       suppress_health_check=list(HealthCheck))
    profile(PROPERTIES[name])()
