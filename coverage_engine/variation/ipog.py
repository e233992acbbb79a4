"""Pairwise covering arrays for many values: IPOG (in-parameter-order), linear in the rows it writes.

The AETG-style builder of :mod:`coverage_engine.variation.pairwise` tries 24 candidate rows per row
and compacts the result, which gives small arrays but costs rows² work: 10 parameters of 50 values
(2,500+ rows) did not finish in 300 s. IPOG (Lei and Tai, 1998) grows the array one parameter at a
time instead: the product of the first two parameters' values; then, for each next parameter, every
row gets the value that covers the most open pairs with the parameters before (*horizontal growth*),
and the pairs still open get rows of their own, sharing a row where its cells are still free
(*vertical growth*). Open pairs are bit masks, one integer per (earlier parameter, value): bit ``w``
of ``open_[i][u]`` says the pair (i = u, new parameter = w) is not covered yet.

Values that do not resolve are never placed; pairs the ``fixed`` rows (written before) cover count as
covered. Free cells left at the end take the axis's first allowed value. ``tick`` is called between
parameters and every few hundred rows, so a caller can show progress and stop on a signal.
"""

from __future__ import annotations

import random
from collections.abc import Callable, Sequence

#: A cell no pair needs yet (vertical growth may still set it).
FREE = -1

#: Rows between two calls of the progress callback during horizontal growth.
TICK_ROWS = 256


def ipog_pairwise(sizes: Sequence[int], allowed: Sequence[Sequence[int]], rng: random.Random,
                  fixed: Sequence[tuple[int, ...]] = (),
                  tick: Callable[[int, int], None] | None = None) -> list[tuple[int, ...]]:
    """Rows covering every pair of allowed values that the ``fixed`` rows do not; ``tick(k, n)`` after
    each parameter ``k`` of ``n`` (and often within one)."""
    n = len(sizes)
    order = sorted(range(n), key=lambda a: -len(allowed[a]))      # most values first: fewest rows
    first, second = order[0], order[1]
    covered = _covered_by(fixed, n)
    rows: list[list[int]] = []
    for u in allowed[first]:
        for w in allowed[second]:
            if not _is_covered(covered, first, u, second, w):
                row = [FREE] * n
                row[first], row[second] = u, w
                rows.append(row)
    for step, new in enumerate(order[2:], start=2):
        earlier = order[:step]
        open_ = _open_pairs(earlier, new, allowed, covered)
        _horizontal(rows, earlier, new, allowed[new], open_, rng, tick, step, n)
        _vertical(rows, earlier, new, allowed, open_, n)
        if tick is not None:
            tick(step + 1, n)
    for row in rows:
        for axis in range(n):
            if row[axis] == FREE:
                row[axis] = allowed[axis][0]
    return [tuple(row) for row in rows]


def _covered_by(fixed: Sequence[tuple[int, ...]], n: int) -> set[tuple[int, int, int, int]]:
    """The pairs ``(a, u, b, w)`` with ``a < b`` that rows written before hold."""
    return {(a, row[a], b, row[b]) for row in fixed for a in range(n) for b in range(a + 1, n)}


def _is_covered(covered: set, a: int, u: int, b: int, w: int) -> bool:
    return (a, u, b, w) in covered if a < b else (b, w, a, u) in covered


def _open_pairs(earlier: Sequence[int], new: int, allowed: Sequence[Sequence[int]],
                covered: set) -> dict[int, dict[int, int]]:
    """Per earlier axis and value, the bit mask of the new axis's values still to pair with it."""
    full = sum(1 << w for w in allowed[new])
    open_: dict[int, dict[int, int]] = {}
    for axis in earlier:
        open_[axis] = {}
        for u in allowed[axis]:
            mask = full
            if covered:
                for w in allowed[new]:
                    if _is_covered(covered, axis, u, new, w):
                        mask &= ~(1 << w)
            open_[axis][u] = mask
    return open_


def _horizontal(rows: list[list[int]], earlier: Sequence[int], new: int, values: Sequence[int],
                open_: dict[int, dict[int, int]], rng: random.Random,
                tick: Callable[[int, int], None] | None, step: int, n: int) -> None:
    """Give every row the new axis's value that covers the most open pairs (ties: the seeded choice)."""
    shuffled = list(values)
    for index, row in enumerate(rows):
        if tick is not None and index % TICK_ROWS == TICK_ROWS - 1:
            tick(step, n)
        masks = [open_[axis][row[axis]] for axis in earlier if row[axis] != FREE]
        counts = dict.fromkeys(values, 0)
        for mask in masks:
            while mask:
                low = mask & -mask
                counts[low.bit_length() - 1] += 1
                mask ^= low
        rng.shuffle(shuffled)
        best = max(shuffled, key=counts.__getitem__)
        if counts[best] == 0:
            continue                     # nothing to gain: the cell stays free for vertical growth
        row[new] = best
        bit = ~(1 << best)
        for axis in earlier:
            u = row[axis]
            if u != FREE:
                open_[axis][u] &= bit


def _vertical(rows: list[list[int]], earlier: Sequence[int], new: int, allowed: Sequence[Sequence[int]],
              open_: dict[int, dict[int, int]], n: int) -> None:
    """Put each pair still open into a row whose cells for it are free (or hold its values), else a new row."""
    # Rows that still have a free cell, by the value of the new axis they hold (FREE: none yet).
    with_free: dict[int, list[list[int]]] = {}
    for row in rows:
        if any(row[axis] == FREE for axis in earlier):
            with_free.setdefault(row[new], []).append(row)
    for axis in earlier:
        for u in allowed[axis]:
            mask = open_[axis][u]
            while mask:
                low = mask & -mask
                w = low.bit_length() - 1
                mask ^= low
                shared = _shared_row(with_free, axis, u, new, w)
                if shared is None:
                    shared = [FREE] * n
                    rows.append(shared)
                    with_free.setdefault(w, []).append(shared)
                elif shared[new] == FREE:
                    with_free[FREE].remove(shared)
                    with_free.setdefault(w, []).append(shared)
                shared[axis], shared[new] = u, w
            open_[axis][u] = 0


def _shared_row(with_free: dict[int, list[list[int]]], axis: int, u: int, new: int,
                w: int) -> list[int] | None:
    """A row that can take the pair (axis = u, new = w) without changing a value it holds."""
    for key in (w, FREE):
        for row in with_free.get(key, ()):
            if row[axis] == FREE or row[axis] == u:
                return row
    return None
