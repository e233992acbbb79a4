"""Failures grouped by reason: twenty failures of three kinds read as three lines, not twenty.

Two failures are of the same kind when their reasons have the same location (``file:line``, the
column dropped) and the same message once numbers, quoted names and hexadecimal ids are masked:
``speed 84.2 above 80`` and ``speed 91.7 above 80`` are one group, ``'ego' collided`` and ``'npc1'
collided`` another. Each group keeps its count, its runs, and the parameter values all its runs
share (what the failures have in common is where to look first).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

#: ``file.ext:line[:col]`` at the start of a reason or after a space (the form our errors are written in).
_LOCATION = re.compile(r"(?:(?<=[\s(\[])|^)([\w./\\-]+\.\w+):(\d+)(?::\d+)?(?::)?")
_QUOTED = re.compile(r"'[^']*'|\"[^\"]*\"")
_HEX = re.compile(r"\b0x[0-9a-fA-F]+\b")
_NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")
#: Characters of a reason kept as a group's message.
MESSAGE_CHARS = 200


@dataclass(frozen=True)
class Failure:
    """One failing run: its name (the variant or attempt), its reason and its varied values."""

    name: str
    reason: str
    values: Mapping[str, object]


@dataclass(frozen=True)
class FailureGroup:
    """Failures of one kind: the masked message, the location, the runs, and the values they share."""

    message: str
    location: str | None
    example: str
    names: tuple[str, ...]
    common: tuple[tuple[str, str], ...]

    @property
    def count(self) -> int:
        return len(self.names)

    def as_dict(self) -> dict[str, object]:
        return {"message": self.message, "location": self.location, "example": self.example, "count": self.count,
                "runs": list(self.names), "common_values": dict(self.common)}


def reason_location(reason: str) -> str | None:
    """The ``file:line`` a reason names (its first), or None."""
    found = _LOCATION.search(" ".join(reason.split()))
    return f"{found.group(1)}:{found.group(2)}" if found else None


def reason_key(reason: str) -> tuple[str, str | None]:
    """``(masked message, location)`` of a reason: the kind of failure it is. The location is the file's
    name (folders dropped, numbers masked: ``cut#.sce``, as every variant of a source is its own file with
    the same lines) and the line."""
    text = " ".join(reason.split())
    found = _LOCATION.search(text)
    location = None
    if found:
        name = found.group(1).replace("\\", "/").rsplit("/", 1)[-1]
        location = f"{_NUMBER.sub('#', name)}:{found.group(2)}"
        text = (text[:found.start()] + text[found.end():]).strip()
    text = _QUOTED.sub("'…'", text)
    text = _NUMBER.sub("#", _HEX.sub("\x00", text)).replace("\x00", "0x…")   # hex ids first: 0x7f3a, not #x#f#a
    return text[:MESSAGE_CHARS], location


def _shown(value: object) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def _common(failures: list[Failure]) -> tuple[tuple[str, str], ...]:
    """The parameter values every failure of the group has (none for a group of one: nothing to compare)."""
    if len(failures) < 2:
        return ()
    first = failures[0].values
    shared = []
    for key, value in first.items():
        if all(key in f.values and f.values[key] == value for f in failures[1:]):
            shared.append((key, _shown(value)))
    return tuple(shared)


def group_failures(failures: Iterable[Failure]) -> list[FailureGroup]:
    """The failures grouped by kind, the largest group first (then by first appearance)."""
    groups: dict[tuple[str, str | None], list[Failure]] = {}
    for failure in failures:
        groups.setdefault(reason_key(failure.reason or "no reason given"), []).append(failure)
    ordered = sorted(groups.items(), key=lambda entry: -len(entry[1]))
    return [FailureGroup(message, location and reason_location(members[0].reason),
                         " ".join(members[0].reason.split())[:MESSAGE_CHARS],
                         tuple(f.name for f in members), _common(members))
            for (message, location), members in ordered]


def triage_lines(groups: list[FailureGroup], *, names: int = 5, limit: int = 10) -> list[str]:
    """The groups as the terminal shows them: count, location and message, some runs, the shared values."""
    if not groups:
        return []
    total = sum(group.count for group in groups)
    lines = [f"--- {total} failure(s) of {len(groups)} kind(s) ---"]
    for group in groups[:limit]:
        lines.append(f"{group.count:>5} x {group.example}")
        more = f" and {group.count - names} more" if group.count > names else ""
        lines.append(f"        runs: {', '.join(group.names[:names])}{more}")
        if group.common:
            lines.append("        all have: " + ", ".join(f"{k.split('.', 1)[-1]}={v}" for k, v in group.common))
    if len(groups) > limit:
        lines.append(f"... and {len(groups) - limit} more kind(s)")
    return lines
