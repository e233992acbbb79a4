"""Checking JUnit files as CI tools do: against Jenkins' ``junit-10.xsd`` (with lxml).

The schema is carried in ``tests/schemas/junit-10.xsd`` (the public jenkinsci/xunit-plugin file, MIT, its
licence notice at the top), so a clone with no ``../shared`` beside it runs these tests.
"""

from __future__ import annotations

import functools
from pathlib import Path

SCHEMA = Path(__file__).resolve().parent / "schemas" / "junit-10.xsd"


@functools.lru_cache(maxsize=1)
def _schema():
    from lxml import etree

    assert SCHEMA.is_file(), f"the JUnit schema is missing: {SCHEMA}"
    return etree.XMLSchema(etree.parse(str(SCHEMA)))


def schema_errors(xml: str | bytes | Path) -> list[str]:
    """The schema's complaints about a JUnit document (text or file); empty when it is valid."""
    from lxml import etree

    data = xml.read_bytes() if isinstance(xml, Path) else xml.encode() if isinstance(xml, str) else xml
    schema = _schema()
    schema.validate(etree.fromstring(data).getroottree())
    return [f"line {e.line}: {e.message}" for e in schema.error_log]


def assert_valid(xml: str | bytes | Path) -> None:
    """Fail with the schema's messages unless ``xml`` validates."""
    errors = schema_errors(xml)
    assert not errors, "\n".join(errors)
