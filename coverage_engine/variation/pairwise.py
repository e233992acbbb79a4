"""Pairwise covering arrays, fast: bit masks for the open pairs, then a compaction pass.

The general t-way builder in :mod:`coverage_engine.variation.strategies` keeps every open tuple in a
set and builds tuples to look them up; for t = 2 the open pairs fit in one integer per (axis, value,
other axis) — bit ``w`` of ``open[a][v][b]`` says the pair (a = v, b = w) is not covered yet — so the
greedy gain of a value is a count of set bits, ten times faster. That leaves time to try more
candidate rows per row (AETG-style: seed with the most needed pair, fill the other axes in a random
order with the value covering most open pairs) and to *compact* the result: a row whose pairs can
all be moved into other rows (changing only positions whose own pairs are covered elsewhere too)
is removed. On 20 parameters of 10 values that gives 196–197 rows, as covertable's 197, in about a
second.
"""

from __future__ import annotations

import random
from collections.abc import Sequence

#: Candidate rows built for each row kept.
CANDIDATES = 24


def pairwise_rows(sizes: Sequence[int], allowed: Sequence[Sequence[int]], rng: random.Random,
                  fixed: Sequence[tuple[int, ...]] = ()) -> list[tuple[int, ...]]:
    """Rows covering every pair of allowed values that the ``fixed`` rows (written before) do not cover."""
    n = len(sizes)
    full = [sum(1 << v for v in allowed[a]) for a in range(n)]
    allowed_sets = [set(values) for values in allowed]
    masks = [[[full[b] if b != a and v in allowed_sets[a] else 0 for b in range(n)] for v in range(sizes[a])]
             for a in range(n)]
    pending = [[sum(bin(m).count("1") for m in masks[a][v]) for v in range(sizes[a])] for a in range(n)]
    remaining = sum(sum(p) for p in pending) // 2
    for earlier in fixed:
        remaining -= _take(earlier, masks, pending)
    rows: list[tuple[int, ...]] = []
    axes = list(range(n))
    while remaining > 0:
        best: list[int] | None = None
        best_gain = -1
        for _ in range(CANDIDATES):
            candidate, gain = _candidate(axes, sizes, allowed, masks, pending, rng)
            if gain > best_gain:
                best, best_gain = candidate, gain
        assert best is not None and best_gain > 0
        remaining -= _take(best, masks, pending)
        rows.append(tuple(best))
    return compact(rows, n, fixed)


def _candidate(axes: list[int], sizes: Sequence[int], allowed: Sequence[Sequence[int]], masks: list, pending: list,
               rng: random.Random) -> tuple[list[int], int]:
    """One greedy row and the number of open pairs it covers."""
    top = max(max(p) for p in pending)
    a, va = rng.choice([(a, v) for a in axes for v in allowed[a] if pending[a][v] == top])
    partners = [(pending[b][w], b, w) for b in axes if b != a for w in allowed[b] if masks[a][va][b] >> w & 1]
    most = max(partners)[0]
    _, b, vb = rng.choice([p for p in partners if p[0] == most])
    row = [-1] * len(axes)
    row[a], row[b] = va, vb
    filled = [a, b]
    gain = 1
    order = [x for x in axes if x != a and x != b]
    rng.shuffle(order)
    for x in order:
        counts = [0] * sizes[x]
        for f in filled:
            m = masks[f][row[f]][x]
            while m:
                low = m & -m
                counts[low.bit_length() - 1] += 1
                m ^= low
        values = list(allowed[x])
        rng.shuffle(values)
        needed = pending[x]
        value = max(values, key=lambda v: (counts[v], needed[v]))
        row[x] = value
        gain += counts[value]
        filled.append(x)
    return row, gain


def _take(row: Sequence[int], masks: list, pending: list) -> int:
    """Mark the pairs of ``row`` covered; returns how many were open."""
    taken = 0
    n = len(row)
    for i in range(n):
        ri = row[i]
        for j in range(i + 1, n):
            rj = row[j]
            if masks[i][ri][j] >> rj & 1:
                masks[i][ri][j] &= ~(1 << rj)
                masks[j][rj][i] &= ~(1 << ri)
                pending[i][ri] -= 1
                pending[j][rj] -= 1
                taken += 1
    return taken


def compact(rows: list[tuple[int, ...]], n: int, fixed: Sequence[tuple[int, ...]] = ()) -> list[tuple[int, ...]]:
    """Remove rows whose pairs other rows can take over, until no more can go (``fixed`` rows never change)."""
    while True:
        smaller = _compact_once(rows, n, fixed)
        if len(smaller) == len(rows):
            return rows
        rows = smaller


def _compact_once(rows: list[tuple[int, ...]], n: int, fixed: Sequence[tuple[int, ...]]) -> list[tuple[int, ...]]:
    """One pass: each row, fewest unique pairs first, goes when other rows can be changed to take its pairs."""
    pairs = _PairCounts(rows, n, fixed)
    for r in sorted(range(len(pairs.table)), key=lambda r: len(pairs.unique(r))):
        pairs.try_remove(r)
    return [tuple(row) for k, row in enumerate(pairs.table) if pairs.alive[k]]


#: One change of a row: (row, axis, value before).
_Change = tuple[int, int, int]


class _PairCounts:
    """The rows being compacted and how many rows (the fixed ones too) hold each pair of values."""

    def __init__(self, rows: list[tuple[int, ...]], n: int, fixed: Sequence[tuple[int, ...]]) -> None:
        self.n = n
        self.table = [list(r) for r in rows]
        self.alive = [True] * len(rows)
        self.count: dict[tuple[int, int, int, int], int] = {}
        for kept in [*fixed, *rows]:
            for i in range(n):
                for j in range(i + 1, n):
                    key = (i, j, kept[i], kept[j])
                    self.count[key] = self.count.get(key, 0) + 1

    @staticmethod
    def pair(i: int, c: int, vi: int, vc: int) -> tuple[int, int, int, int]:
        return (i, c, vi, vc) if i < c else (c, i, vc, vi)

    def change(self, k: int, axis: int, new: int, log: list[_Change]) -> bool:
        """Set row ``k``'s ``axis`` to ``new`` if every pair it holds there is covered elsewhere too."""
        row, count, pair = self.table[k], self.count, self.pair
        old = row[axis]
        if old == new:
            return True
        if any(count[pair(axis, c, old, row[c])] < 2 for c in range(self.n) if c != axis):
            return False
        for c in range(self.n):
            if c != axis:
                count[pair(axis, c, old, row[c])] -= 1
                key = pair(axis, c, new, row[c])
                count[key] = count.get(key, 0) + 1
        row[axis] = new
        log.append((k, axis, old))
        return True

    def undo(self, log: list[_Change]) -> None:
        """Take the changes of ``log`` back, last first."""
        for k, axis, old in reversed(log):
            row = self.table[k]
            new = row[axis]
            for c in range(self.n):
                if c != axis:
                    self.count[self.pair(axis, c, new, row[c])] -= 1
                    self.count[self.pair(axis, c, old, row[c])] += 1
            row[axis] = old

    def unique(self, r: int) -> list[tuple[int, int]]:
        """The axis pairs whose values row ``r`` alone holds."""
        row, n = self.table[r], self.n
        return [(i, j) for i in range(n) for j in range(i + 1, n) if self.count[(i, j, row[i], row[j])] == 1]

    def try_remove(self, r: int) -> None:
        """Move each pair only row ``r`` holds into another live row; drop ``r`` if all moved, else undo."""
        row, n, count = self.table[r], self.n, self.count
        log: list[_Change] = []
        moved = True
        for i, j in self.unique(r):
            if count[(i, j, row[i], row[j])] >= 2:
                continue
            targets = sorted((k for k in range(len(self.table)) if k != r and self.alive[k]),
                             key=lambda k: (self.table[k][i] != row[i]) + (self.table[k][j] != row[j]))
            for k in targets:
                step: list[_Change] = []
                if self.change(k, i, row[i], step) and self.change(k, j, row[j], step):
                    log += step
                    break
                self.undo(step)
            else:
                moved = False
                break
        if moved and all(count[(i, j, row[i], row[j])] >= 2 for i in range(n) for j in range(i + 1, n)):
            for i in range(n):
                for j in range(i + 1, n):
                    count[(i, j, row[i], row[j])] -= 1
            self.alive[r] = False
        else:
            self.undo(log)
