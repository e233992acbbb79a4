"""Where something stands in a source file: the one position type of syntax nodes, the model and errors.

It sits below the parse/resolve/files layers because every one of them (and the exception tree) points
at the source.
"""

from __future__ import annotations

from coverage_engine.records import Record, record

#: The line of a location that names its file as a whole (:meth:`Location.whole_file`); real lines are 1-based.
WHOLE_FILE_LINE = 0


@record
class Location(Record):
    """Where a node stands in its file: 1-based line/column of its start and end, and 0-based offsets.

    ``start_pos``/``end_pos`` index the file's text (as read, after CRLF was kept) so tools such as the
    variation generator can cut and replace the exact source of a node. A location of the file as a whole
    is made by :meth:`whole_file` and says so by :attr:`is_whole_file`.
    """

    file: str
    line: int
    column: int
    end_line: int = 0
    end_column: int = 0
    start_pos: int = 0
    end_pos: int = 0

    @classmethod
    def whole_file(cls, file: str) -> Location:
        """The file as a whole, no position in it (a file that cannot be read, a document of the wrong
        shape): it renders as ``file`` alone, and a message about it as ``file: error: …``."""
        return cls(file, WHOLE_FILE_LINE, 0)

    @classmethod
    def at(cls, file: str, line: int, column: int) -> Location:
        """``line``:``column`` of ``file`` when the line is known (1-based), else the whole file: for
        readers (YAML, JSON) that report a position only for some of their errors."""
        return cls(file, line, column) if line >= 1 else cls.whole_file(file)

    @property
    def is_whole_file(self) -> bool:
        """Whether this names the file as a whole rather than a place in it."""
        return self.line == WHOLE_FILE_LINE

    def __str__(self) -> str:
        if self.line == WHOLE_FILE_LINE:
            return self.file
        return f"{self.file}:{self.line}:{self.column}"
