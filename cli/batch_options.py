"""The value types of ``scenario_batch_execution``'s own options: ``-j N|auto``, ``--shard i/N`` and
``--repeat N|until-fail:N``. Each converts the text once, and says what is wrong as the option's usage error."""

from __future__ import annotations

from typing import TYPE_CHECKING

import click

if TYPE_CHECKING:
    from executor.batch.inputs import Shard


def _count(kind: click.ParamType, text: str, given: object, other: str, param: click.Parameter | None,
           ctx: click.Context | None) -> int:
    """``text`` as a whole number of at least 1; else the option's usage error (``other``: the other form
    the option takes)."""
    try:
        number = int(text)
    except ValueError:
        kind.fail(f"{given!r} is neither a number nor {other}", param, ctx)
    if number < 1:
        kind.fail(f"{number} must be at least 1", param, ctx)
    return number


class JobsType(click.ParamType):
    """``-j``: a positive number of parallel jobs, or ``auto`` for the number of CPUs this process may use."""

    name = "N|auto"

    def convert(self, value: object, param: click.Parameter | None, ctx: click.Context | None) -> int:
        if isinstance(value, int):
            return value
        if str(value).lower() == "auto":
            from executor.batch.builtin_runner import usable_cpus

            return usable_cpus()
        return _count(self, str(value), value, "'auto'", param, ctx)


class ShardType(click.ParamType):
    """``--shard i/N``: the i-th of N subsets, 1 <= i <= N."""

    name = "i/N"

    def convert(self, value: object, param: click.Parameter | None, ctx: click.Context | None) -> Shard:
        from executor.batch.errors import BadShard
        from executor.batch.inputs import Shard

        if isinstance(value, Shard):
            return value
        try:
            return Shard.parse(str(value))
        except BadShard as exc:
            self.fail(str(exc).removeprefix("--shard "), param, ctx)


class RepeatType(click.ParamType):
    """``--repeat``: ``N`` attempts of each variant, or ``until-fail:N`` (stop a variant at its first failure);
    converts to ``(N, until_fail)``."""

    name = "N|until-fail:N"

    def convert(self, value: object, param: click.Parameter | None,
                ctx: click.Context | None) -> tuple[int, bool]:
        if isinstance(value, tuple):
            return value
        text = str(value).strip()
        until_fail = text.lower().startswith("until-fail:")
        number = text.split(":", 1)[1] if until_fail else text
        return _count(self, number, value, "'until-fail:N'", param, ctx), until_fail
