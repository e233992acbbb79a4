"""Where something stands in a source file: the one position type of syntax nodes, the model and errors.

It sits below the parse/resolve/files layers because every one of them (and the exception tree) points
at the source.
"""

from __future__ import annotations

from coverage_engine.records import Record, record


@record
class Location(Record):
    """Where a node stands in its file: 1-based line/column of its start and end, and 0-based offsets.

    ``start_pos``/``end_pos`` index the file's text (as read, after CRLF was kept) so tools such as the
    variation generator can cut and replace the exact source of a node.
    """

    file: str
    line: int
    column: int
    end_line: int = 0
    end_column: int = 0
    start_pos: int = 0
    end_pos: int = 0

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"
