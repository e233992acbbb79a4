"""Options and value types that several commands share, defined once: ``--store``, ``-d/--debug``, seconds."""

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
