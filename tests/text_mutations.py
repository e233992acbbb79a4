"""A hypothesis strategy shared by the property tests of our readers: a text cut and spliced at random."""

from __future__ import annotations

from collections.abc import Sequence

from hypothesis import strategies as st


@st.composite
def mutated(draw, sources: Sequence[str], pieces: Sequence[str]) -> str:
    """One of ``sources`` with 1 to 4 edits: a piece of ``pieces`` put in, or 1 to 6 characters taken out."""
    text = draw(st.sampled_from(list(sources)))
    for _ in range(draw(st.integers(1, 4))):
        at = draw(st.integers(0, len(text)))
        if draw(st.booleans()):
            text = text[:at] + draw(st.sampled_from(list(pieces))) + text[at:]
        else:
            text = text[:at] + text[at + draw(st.integers(1, 6)):]
    return text
