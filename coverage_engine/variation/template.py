"""The source text of a file cut into fixed pieces and one slot per dimension.

A concrete variant is ``chunks[0] + slot_0 + chunks[1] + … + chunks[n]``, where slot ``i`` is
``<left> == <value>`` for the chosen value of dimension ``i``. Building a variant is a string join:
no parsing, no tree copying.

Line numbers are kept: when a value list spanned several lines, the lines it took are given back as
blank lines right after the line the constraint ends on. So every line of a concrete variant (and of
its ``.sce`` model) has the number it has in the ``.osc``, and an error found in one variant points at
the line the user wrote.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from coverage_engine.lazy import NumberTexts
from coverage_engine.variation.dimensions import Dimension
from coverage_engine.variation.drawn import DrawnChoices


@dataclass(frozen=True)
class TextTemplate:
    """``chunks`` (one more than dimensions) and, per dimension, the replacement text of each choice."""

    chunks: tuple[str, ...]
    replacements: tuple[Sequence[str], ...]

    @classmethod
    def build(cls, text: str, dimensions: Sequence[Dimension]) -> TextTemplate:
        """Cut ``text`` at the ``in`` expressions of ``dimensions`` (sorted, non-overlapping).

        The text is given a single final line break (what a ``.sce`` model block keeps).
        """
        chunks: list[str] = []
        position = 0
        owed = 0  # line breaks removed by replacements and not yet given back
        for dim in dimensions:
            chunk = text[position:dim.start]
            chunk, owed = _give_back(chunk, owed)
            chunks.append(chunk)
            owed += text.count("\n", dim.start, dim.end)
            position = dim.end
        tail = text[position:].rstrip("\n") + "\n"
        tail, owed = _give_back(tail, owed)
        chunks.append(tail + "\n" * owed)
        replacements = tuple(_replacements(dim) for dim in dimensions)
        return cls(tuple(chunks), replacements)

    def render(self, choices: Sequence[int]) -> str:
        """The concrete text for one choice index per dimension (extra trailing entries are ignored)."""
        chunks = self.chunks
        parts = [chunks[0]]
        for i, slot in enumerate(self.replacements):
            parts.append(slot[choices[i]])
            parts.append(chunks[i + 1])
        return "".join(parts)


def _replacements(dim: Dimension) -> Sequence[str]:
    """The replacement text of each choice; for drawn values formatted from the number when asked for."""
    choices = dim.choices
    if isinstance(choices, DrawnChoices):
        return NumberTexts(choices.values, f"{dim.left} == ", choices.spec.unit)
    return tuple(dim.replacement(i) for i in range(len(choices)))


def _give_back(chunk: str, owed: int) -> tuple[str, int]:
    """Insert ``owed`` line breaks at the first line break of ``chunk`` (if it has one)."""
    if owed == 0:
        return chunk, 0
    at = chunk.find("\n")
    if at < 0:
        return chunk, owed
    return chunk[:at] + "\n" * owed + chunk[at:], 0
