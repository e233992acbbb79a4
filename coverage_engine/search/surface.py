"""A smooth estimate of where pass turns to fail: logistic regression on the quadratic terms of the axes.

Bisection alone puts a new run halfway between two runs that disagree, so a round's runs land up to
half a gap from the boundary. Most boundaries of a physical scenario are smooth (a braking distance is
a quadratic in the speed), and a quadratic surface fitted to every run's side says where the gap is
crossed better than its middle does. The fit is regularised logistic regression solved by Newton's
method (a few iterations over ``1 + d + d(d+1)/2`` terms), pure Python: a search reads at most thousands
of runs, and the core has no numeric dependency. Runs that separate perfectly (the usual case: a
verdict is not noisy) keep finite weights through the regularisation.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

#: L2 regularisation of the fitted weights (keeps them finite when the runs separate perfectly).
REGULARISATION = 1e-3

#: Newton iterations of the fit.
FIT_STEPS = 25


def _terms(point: Sequence[float]) -> list[float]:
    """1, each coordinate, and each product of two coordinates (squares included)."""
    x = list(point)
    return [1.0, *x, *(x[i] * x[j] for i, j in itertools.combinations_with_replacement(range(len(x)), 2))]


def _solve(matrix: list[list[float]], vector: list[float]) -> list[float] | None:
    """``matrix⁻¹ · vector`` by Gaussian elimination with partial pivoting (None when singular)."""
    n = len(vector)
    rows = [row[:] + [v] for row, v in zip(matrix, vector, strict=True)]
    for col in range(n):
        pivot = max(range(col, n), key=lambda r: abs(rows[r][col]))
        if abs(rows[pivot][col]) < 1e-12:
            return None
        rows[col], rows[pivot] = rows[pivot], rows[col]
        for r in range(col + 1, n):
            factor = rows[r][col] / rows[col][col]
            if factor:
                for c in range(col, n + 1):
                    rows[r][c] -= factor * rows[col][c]
    solution = [0.0] * n
    for r in range(n - 1, -1, -1):
        solution[r] = (rows[r][n] - sum(rows[r][c] * solution[c] for c in range(r + 1, n))) / rows[r][r]
    return solution


@dataclass(frozen=True)
class Surface:
    """``score(x) > 0`` on the failing side; the boundary is where the score is 0."""

    weights: tuple[float, ...]

    def score(self, point: Sequence[float]) -> float:
        return sum(w * t for w, t in zip(self.weights, _terms(point), strict=True))

    def crossing(self, a: Sequence[float], b: Sequence[float]) -> float | None:
        """Where on the segment from ``a`` to ``b`` (0..1) the score is 0, if it is (the nearest to the middle)."""
        f0, fh, f1 = self.score(a), self.score([(x + y) / 2 for x, y in zip(a, b, strict=True)]), self.score(b)
        # the score along the segment is a quadratic in t: f(t) = c0 + c1 t + c2 t²
        c0, c2 = f0, 2 * (f1 + f0 - 2 * fh)
        c1 = f1 - f0 - c2
        roots: list[float] = []
        if abs(c2) < 1e-12:
            if abs(c1) > 1e-12:
                roots = [-c0 / c1]
        else:
            disc = c1 * c1 - 4 * c2 * c0
            if disc >= 0:
                root = math.sqrt(disc)
                roots = [(-c1 - root) / (2 * c2), (-c1 + root) / (2 * c2)]
        inside = [t for t in roots if 0.0 <= t <= 1.0]
        return min(inside, key=lambda t: abs(t - 0.5)) if inside else None

    def onto(self, point: Sequence[float], steps: int = 6) -> list[float] | None:
        """``point`` moved along the score's gradient onto the surface (None when it does not get there)."""
        here = list(point)
        for _ in range(steps):
            value = self.score(here)
            gradient = self._gradient(here)
            size = sum(g * g for g in gradient)
            if size < 1e-18:
                return None
            here = [x - value * g / size for x, g in zip(here, gradient, strict=True)]
        scale = math.sqrt(sum(g * g for g in self._gradient(here))) or 1.0
        return here if abs(self.score(here)) / scale < 1e-6 else None

    def _gradient(self, point: Sequence[float]) -> list[float]:
        step = 1e-6
        base = self.score(point)
        out = []
        for axis in range(len(point)):
            moved = list(point)
            moved[axis] += step
            out.append((self.score(moved) - base) / step)
        return out


def fit_surface(points: Sequence[Sequence[float]], failing: Sequence[bool]) -> Surface | None:
    """The quadratic logistic surface that best separates the failing runs from the passing ones (None
    when one side has no run, or the fit cannot be solved)."""
    if not points or all(failing) or not any(failing):
        return None
    rows = [_terms(p) for p in points]
    labels = [1.0 if f else 0.0 for f in failing]
    size = len(rows[0])
    weights = [0.0] * size
    for _ in range(FIT_STEPS):
        hessian = [[REGULARISATION if i == j else 0.0 for j in range(size)] for i in range(size)]
        gradient = [REGULARISATION * w for w in weights]
        for row, label in zip(rows, labels, strict=True):
            z = sum(w * t for w, t in zip(weights, row, strict=True))
            p = 1.0 / (1.0 + math.exp(-max(-60.0, min(60.0, z))))
            weight = max(p * (1 - p), 1e-12)
            for i in range(size):
                gradient[i] += (p - label) * row[i]
                ri = weight * row[i]
                for j in range(i, size):
                    hessian[i][j] += ri * row[j]
        for i in range(size):
            for j in range(i):
                hessian[i][j] = hessian[j][i]
        step = _solve(hessian, gradient)
        if step is None:
            return None
        weights = [w - s for w, s in zip(weights, step, strict=True)]
        if max(abs(s) for s in step) < 1e-8:
            break
    return Surface(tuple(weights))
