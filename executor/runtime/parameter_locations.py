"""Point a parameter-file error at the key it is about.

The resolver checks a parameter document against the scenarios but knows nothing of the YAML text,
so its :class:`~coverage_engine.errors.ParameterFileError` carries no location; the message names
the keys in quotes (``scenario 'x' has no parameter 'nosuch'``, ``parameter 'x.speed': …``). Only
when such an error happens is the file composed again (``yaml.compose_all`` keeps line and column of
every node) and the deepest key path the quoted names spell is looked up in the failing document.
Without a match the error points at the document (or the whole file).
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from coverage_engine.location import Location

if TYPE_CHECKING:   # PyYAML is imported when a parameter file is read
    import yaml

_QUOTED = re.compile(r"'([^'\n]+)'")


def key_marks(document_node: yaml.Node) -> dict[str, tuple[int, int]]:
    """``"scenario.param.member"`` / ``"…list[2]"`` → ``(line, column)`` (1-based) of each key or item."""
    import yaml

    marks: dict[str, tuple[int, int]] = {}

    def walk(node: yaml.Node, prefix: str) -> None:
        if isinstance(node, yaml.MappingNode):
            for key_node, value_node in node.value:
                if not isinstance(key_node, yaml.ScalarNode):
                    continue
                path = f"{prefix}.{key_node.value}" if prefix else str(key_node.value)
                marks.setdefault(path, (key_node.start_mark.line + 1, key_node.start_mark.column + 1))
                walk(value_node, path)
        elif isinstance(node, yaml.SequenceNode) and prefix:
            for index, item in enumerate(node.value):
                path = f"{prefix}[{index}]"
                marks.setdefault(path, (item.start_mark.line + 1, item.start_mark.column + 1))
                walk(item, path)

    walk(document_node, "")
    return marks


def best_key(message: str, marks: dict[str, tuple[int, int]]) -> str | None:
    """The deepest known key path spelled by the quoted names of ``message`` (read left to right)."""
    best: str | None = None
    for name in _QUOTED.findall(message):
        for candidate in ((f"{best}.{name}" if best else None), name):
            if candidate and candidate in marks and (best is None or len(candidate) > len(best)):
                best = candidate
                break
    return best


def locate(path: str, document_index: int, message: str) -> tuple[Location, str | None]:
    """Where in the parameter file ``path`` the error ``message`` about document ``document_index`` is.

    Returns the location and the source line (for the caret), or the whole file when nothing fits.
    """
    import yaml

    whole_file = Location.whole_file(str(path))
    try:
        with open(path, encoding="utf-8") as handle:
            text = handle.read()
        nodes = list(yaml.compose_all(text, Loader=yaml.SafeLoader))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return whole_file, None
    if not 0 <= document_index < len(nodes) or nodes[document_index] is None:
        return whole_file, None
    node = nodes[document_index]
    marks = key_marks(node)
    key = best_key(message, marks)
    if key is None:
        line, column = node.start_mark.line + 1, node.start_mark.column + 1
    else:
        line, column = marks[key]
    lines = text.splitlines()
    return Location(str(path), line, column), (lines[line - 1] if 1 <= line <= len(lines) else None)
