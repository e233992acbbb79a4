"""How big a covering array will be, known before it is built, and refused when it is too big.

A covering array of strength t has at least as many rows as the t largest dimensions have value
combinations (each of those must be a row of its own). The general t-way builder also keeps every
t-tuple still open in memory: t = 3 over 40 dimensions of 50 values is 9,880 groups of 125,000
tuples, 1.2 billion, which ended in a MemoryError at 3.9 GB after 48 s. Both numbers take
microseconds to compute (the tuple count is the t-th elementary symmetric sum of the sizes), so a
strategy beyond ``--max-variants`` or beyond :data:`MAX_OPEN_TUPLES` is refused up front with the
estimate and what to do instead.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

#: Most t-tuples the general (t-way, or pairwise with keep conditions) builder may track at once
#: (a set entry each: about 150 bytes, so 300 MB at the limit).
MAX_OPEN_TUPLES = 2_000_000


@dataclass(frozen=True)
class CoveringEstimate:
    """The size of a covering array before it is built."""

    strength: int
    dimensions: int
    #: Rows it has at least: the product of the t largest dimensions.
    least_rows: int
    #: t-tuples of values to cover (the sum, over every t dimensions, of their product).
    tuples: int


def estimate(sizes: Sequence[int], strength: int) -> CoveringEstimate:
    """The estimate for dimensions of ``sizes`` values at strength ``strength``."""
    least = math.prod(sorted(sizes, reverse=True)[:strength])
    sums = [1] + [0] * strength                  # elementary symmetric sums, built one dimension at a time
    for size in sizes:
        for j in range(strength, 0, -1):
            sums[j] += sums[j - 1] * size
    return CoveringEstimate(strength, len(sizes), least, sums[strength])


def refusal(found: CoveringEstimate, limit: int, tracks_tuples: bool) -> str | None:
    """Why the array is not built (None: it is): beyond ``--max-variants`` or beyond the tuples the
    general builder can hold."""
    t = found.strength
    what = f"{'pairwise' if t == 2 else f't-way --strength {t}'} over {found.dimensions} dimensions"
    if found.least_rows > limit:
        return (f"{what} needs at least {found.least_rows:,} variants (the {t} largest dimensions' "
                f"combinations), more than --max-variants ({limit:,}); nothing was written")
    if tracks_tuples and found.tuples > MAX_OPEN_TUPLES:
        return (f"{what} has {found.tuples:,} {t}-tuples to cover (at least {found.least_rows:,} variants), "
                f"more than the {MAX_OPEN_TUPLES:,} this builder can track; nothing was written")
    return None


def alternatives(found: CoveringEstimate, limit: int) -> str:
    """What to run instead of a refused covering array."""
    lower = "" if found.strength == 2 else (
        f"--strength {found.strength - 1}, " if found.strength > 3 else "--strategy pairwise, ")
    more = (f", or --max-variants {found.least_rows} if that many variants are wanted"
            if found.least_rows > limit else "")
    return f"use {lower}fewer values per dimension, or a sample (--strategy lhs --samples N){more}"
