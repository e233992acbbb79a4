"""How testcases are named in every ``test.xml`` we write (one scheme for single runs and batches).

CI pages group testcases by ``classname`` and list them by ``name``, and the pages of GitLab and
GitHub show nothing else (no suite properties). So:

* ``classname`` is the **source scenario**: ``<source file stem>.<scenario name>``, e.g. ``cut.cut_in``
  (Jenkins shows it as package ``cut``, class ``cut_in``). All variants of one scenario share it.
* ``name`` is the **run**: for a scenario of an ``.osc`` file the scenario's run name (``cut_in``,
  or ``cut_in-1`` for the second parameter document); for a variant (a ``.sce`` file) the variant's
  file stem with a short form of its varied values, e.g. ``cut4[gap=2.0s,n=2]``: keys lose their
  ``<scenario>.`` prefix, and the whole name is cut to at most :data:`MAX_NAME_CHARS` characters
  (ending in ``…]``). The stem keeps names unique; the values tell a reader which variant failed.
* a testsuite is named after the scenario file's stem (``cut4``), so reports merged by another tool
  still tell the files apart.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Mapping
from pathlib import PurePath

from coverage_engine.domains import drawn_text, drawn_units_of, header_domains

#: Longest testcase name written (CI pages cut long names; the stem at its start keeps it unique).
MAX_NAME_CHARS = 120

_ELLIPSIS = "…"


@functools.lru_cache(maxsize=256)
def scenario_classname(source_file: str, scenario: str | None) -> str:
    """``<stem of the source .osc>.<scenario>`` (just the stem when the scenario is not known)."""
    stem = PurePath(source_file).stem or source_file
    return f"{stem}.{scenario}" if scenario else stem


def _short_key(key: str, scenario: str | None) -> str:
    if scenario and key.startswith(scenario + "."):
        return key[len(scenario) + 1:]
    return key


def _value_text(value: object) -> str:
    """A varied value on one line: strings as they are, numbers as Python writes them, true/false."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return "null"
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    text = value if isinstance(value, str) else str(value)
    return " ".join(text.split()) if any(c.isspace() and c != " " for c in text) else text


@functools.lru_cache(maxsize=64)
def drawn_units(header: str) -> dict[str, str]:
    """The unit of each parameter a sampler drew, from the ``# domain`` lines of a ``.sce`` header (the
    variants of one variation share their header: read once, not once per job). Do not change the result."""
    return drawn_units_of(header_domains(header))


def _shown(key: str, value: object, drawn: Mapping[str, str]) -> str:
    unit = drawn.get(key)
    if unit is not None and isinstance(value, float) and math.isfinite(value):
        return drawn_text(value, unit)      # 4 significant digits; the properties keep the exact value
    return _value_text(value)


def variant_name(stem: str, assignment: Mapping[str, object] | None, scenario: str | None = None,
                 drawn: Mapping[str, str] | None = None) -> str:
    """``stem[key=value,…]`` for a variant, at most :data:`MAX_NAME_CHARS` characters; ``stem`` without values.

    ``drawn`` maps the parameters a sampler drew to their unit: those values are rounded (``speed=116.2kph``).
    """
    if not assignment:
        return stem
    drawn = drawn or {}
    inner = ",".join(f"{_short_key(str(k), scenario)}={_shown(str(k), v, drawn)}" for k, v in assignment.items())
    name = f"{stem}[{inner}]"
    if len(name) <= MAX_NAME_CHARS:
        return name
    room = MAX_NAME_CHARS - len(stem) - len("[]") - len(_ELLIPSIS)
    if room <= 0:
        return stem[:MAX_NAME_CHARS - len(_ELLIPSIS)] + _ELLIPSIS
    return f"{stem}[{inner[:room]}{_ELLIPSIS}]"


def file_stem(path: str) -> str:
    """The stem of a scenario file's name (what suites, job folders and variant names start with)."""
    return PurePath(path).stem or path


_SCENARIO_LINE = re.compile(r"^scenario[ \t]+([A-Za-z_][\w.]*)", re.MULTILINE)


def declared_scenarios(osc_text: str) -> list[str]:
    """The names of the scenarios an ``.osc`` text declares at the top level (a quick look, no parsing)."""
    return _SCENARIO_LINE.findall(osc_text)
