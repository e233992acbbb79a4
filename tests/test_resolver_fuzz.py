"""Property test: mutated example files either load (parse + resolve) or fail with a located OscError.

The same mutations as the parser's property test, taken one pass further: what parses must also
resolve or be rejected by the resolver with a position, never with another exception.
"""

from __future__ import annotations

import itertools
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from test_parser_fuzz import mutated

from coverage_engine.errors import OscError
from coverage_engine.files.loader import load_scenario_file

_counter = itertools.count()


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_mutations_load_or_fail_with_a_located_error(text):
    with tempfile.TemporaryDirectory(prefix="resolver_fuzz_") as work:
        path = Path(work) / f"fuzz{next(_counter)}.osc"
        path.write_text(text, encoding="utf-8")
        try:
            load_scenario_file(path)
        except OscError as exc:
            assert exc.location is not None, exc.render()
            assert exc.location.line >= 1 and exc.location.column >= 1
            exc.render()
