"""Options and value types that several commands share, defined once: ``--store``, ``-d/--debug``, seconds,
and the options of an adaptive search's goal."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, TypeVar

import click

from cli.boundary import Boundary

F = TypeVar("F", bound=Callable[..., Any])

#: Environment variable naming the store when ``--store`` is not given.
STORE_ENV = "SCENARIO_STORE"


def store_option(func: F) -> F:
    """``--store URL`` (or ``$SCENARIO_STORE``), passed as ``store_url``."""
    return click.option("--store", "store_url", metavar="URL", envvar=STORE_ENV,
                        help=f"SQLAlchemy URL of the store (default: ${STORE_ENV}, else "
                             "./.scenario_store.db).")(func)


def _remember_debug(ctx: click.Context, _param: click.Parameter, value: bool) -> bool:
    """Tell the error boundary (the context's ``obj``) to show tracebacks."""
    boundary = ctx.find_root().obj
    if value and isinstance(boundary, Boundary):
        boundary.show_tracebacks()
    return value


def debug_option(func: F) -> F:
    """``-d/--debug``: debug output, and tracebacks with error messages."""
    return click.option("-d", "--debug", is_flag=True, is_eager=True, callback=_remember_debug,
                        help="Debug output, and tracebacks of errors.")(func)


def goal_options(func: F) -> F:
    """The options that say what an adaptive round looks for (``scenario_variation --from`` and
    ``scenario_search`` alike): ``--objective``, ``--maximise``, ``--threshold``, ``--resolution``,
    ``--pass-rate`` and ``--along``."""
    from coverage_engine.search import DEFAULT_RESOLUTION

    options = [
        click.option("--objective", metavar="NAME",
                     help="falsify: the record() item to minimise, or 'margin' (how close the compare checks came to "
                          "flipping; the default); boundary with --threshold: the record() item that crosses it."),
        click.option("--maximise", is_flag=True, help="falsify: maximise the objective instead of minimising it."),
        click.option("--threshold", type=float, metavar="X",
                     help="boundary: the record() item of --objective below X counts as failing (instead of the "
                          "verdict)."),
        click.option("--resolution", type=click.FloatRange(min=0, max=1, min_open=True), default=DEFAULT_RESOLUTION,
                     show_default=True, metavar="F", help="boundary: locate it to this fraction of each range."),
        click.option("--pass-rate", type=click.FloatRange(min=0, max=1, min_open=True), metavar="R",
                     help="boundary: seek the level of --along KEY where the share of passing runs over the other "
                          "parameters crosses R (e.g. 0.5), instead of where single runs flip."),
        click.option("--along", metavar="KEY",
                     help="boundary with --pass-rate: the varied parameter (its key, or a dotted part of it) whose "
                          "level is sought."),
    ]
    for option in reversed(options):
        func = option(func)
    return func


#: Longest duration any option accepts: a year. Timers are threads' waits, which fail beyond
#: ``threading.TIMEOUT_MAX`` (``--timeout 1e308`` crashed the timer thread); no run needs more.
MAX_SECONDS = 365 * 24 * 3600.0


class Seconds(click.ParamType):
    """A finite number of seconds above 0, at least ``minimum`` and at most ``maximum`` (a year by default).

    ``nan`` and ``inf`` are refused: they would silently disable a limit (``nan`` compares false to all).
    """

    name = "seconds"

    def __init__(self, minimum: float | None = None, maximum: float | None = MAX_SECONDS) -> None:
        self.minimum = minimum
        self.maximum = maximum

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> float:
        try:
            number = float(value)
        except (TypeError, ValueError):
            self.fail(f"{value!r} is not a number of seconds", param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number of seconds", param, ctx)
        if number <= 0:
            self.fail(f"must be more than 0 s (got {value})", param, ctx)
        if self.minimum is not None and number < self.minimum:
            self.fail(f"must be at least {self.minimum:g} s (got {value})", param, ctx)
        if self.maximum is not None and number > self.maximum:
            self.fail(f"must be at most {self.maximum:.10g} s (got {value})", param, ctx)
        return number
