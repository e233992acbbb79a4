"""Property test: mutated .osc files either parse or fail with one of our errors carrying a location."""

from __future__ import annotations

import re
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from coverage_engine.errors import OscError
from coverage_engine.parse.parser import parse_text

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = [
    "scenario a:\n    x: speed = 1.5mps with:\n        keep(it in [1mps..2mps])\n    do serial:\n"
    "        l: log('a' + \"b\")\n        wait elapsed(3s)\n        emit done\n",
    "struct p:\n    x: length = 0m\n    def f(n: int = 1) -> int is external m.f()\n"
    "enum e: [a, b = 2]\nglobal g: e = e!a\n",
]
SOURCES = [p.read_text(encoding="utf-8") for p in sorted((ROOT / "coverage_engine" / "osc").glob("*.osc"))]
SOURCES += [p.read_text(encoding="utf-8") for p in sorted((ROOT / "examples").rglob("*.osc"))]
SOURCES += SAMPLES
TOKEN = re.compile(r"\s+|\w+|[^\w\s]")


@st.composite
def mutated(draw):
    text = draw(st.sampled_from(SOURCES))
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["del_tok", "dup_tok", "swap_tok", "del_line", "dup_line",
                                     "swap_line", "indent", "dedent", "insert"]))
        if kind.endswith("tok"):
            parts = TOKEN.findall(text)
        else:
            parts = text.splitlines(keepends=True)
        if not parts:
            continue
        i = draw(st.integers(0, len(parts) - 1))
        j = draw(st.integers(0, len(parts) - 1))
        if kind.startswith("del"):
            del parts[i]
        elif kind.startswith("dup"):
            parts.insert(i, parts[i])
        elif kind.startswith("swap"):
            parts[i], parts[j] = parts[j], parts[i]
        elif kind == "indent":
            parts[i] = draw(st.sampled_from([" ", "  ", "\t", "    "])) + parts[i]
        elif kind == "dedent":
            parts[i] = parts[i].lstrip(" \t")
        else:
            parts.insert(i, draw(st.sampled_from(["(", ")", "[", "]", ":", "'", '"', "\n", "|", "@", "!", "..",
                                                  "keep", "with:", "do", "-", "#", "\\", "\r"])))
        text = "".join(parts)
    return text


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_mutations_parse_or_fail_with_a_located_error(text):
    try:
        parse_text(text, "fuzz.osc")
    except OscError as exc:
        assert exc.location is not None
        assert exc.location.line >= 1 and exc.location.column >= 1
        exc.render()
