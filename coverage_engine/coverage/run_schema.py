"""Check a decoded ``coverage.json`` document against the schema and build its records.

Every problem is an :class:`Invalid` carrying the JSON path of the bad value (``items[3].range``);
:mod:`run_file` turns it into a :class:`RunFileError` at the value's line and column.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from coverage_engine.coverage.buckets import MAX_BUCKETS, default_every, range_bucket_count
from coverage_engine.coverage.run_records import (
    FORMAT,
    ITEM_KINDS,
    MAX_ITEMS,
    MAX_MEMBERS,
    MAX_NAME_CHARS,
    MAX_SAMPLES_PER_ITEM,
    MAX_TEXT_CHARS,
    READABLE_VERSIONS,
    VERDICTS,
    ItemDecl,
    RunCoverage,
    RunInfo,
)
from coverage_engine.coverage.values import KINDS, ValueType
from coverage_engine.results.files import COVERAGE_FILE


class Invalid(Exception):
    """A value that does not fit the schema, at ``path``."""

    def __init__(self, path: Sequence[str | int], message: str) -> None:
        super().__init__(message)
        self.path = tuple(path)
        self.message = message


def path_text(path: Sequence[str | int]) -> str:
    out = ""
    for step in path:
        out += f"[{step}]" if isinstance(step, int) else (f".{step}" if out else step)
    return out


def _obj(value: object, path: tuple, what: str) -> dict:
    if not isinstance(value, dict):
        raise Invalid(path, f"{what} must be an object")
    return value


def _str(value: object, path: tuple, *, optional: bool = False, limit: int = MAX_TEXT_CHARS) -> str | None:
    if value is None and optional:
        return None
    if not isinstance(value, str):
        raise Invalid(path, "must be a string" + (" or null" if optional else ""))
    if len(value) > limit:
        raise Invalid(path, f"is longer than {limit} characters")
    return value


def _number(value: object, path: tuple) -> float:
    if (type(value) is int or type(value) is float) and math.isfinite(value):
        return value
    raise Invalid(path, "must be a finite number")


def _unknown_keys(data: dict, allowed: set[str], path: tuple) -> None:
    for key in data:
        if key not in allowed:
            raise Invalid((*path, key), f"unknown key '{key}' (known: {', '.join(sorted(allowed))})")


_RUN_KEYS = {"scenario", "verdict", "source", "variant", "assignment", "reason", "started", "duration"}
_ITEM_KEYS = {"name", "kind", "path", "type", "members", "unit", "range", "every", "event", "text", "ignore",
              "items", "samples", "ignored", "unsampled"}


def _run_info(data: object) -> RunInfo:
    p = ("run",)
    run = _obj(data, p, "'run'")
    _unknown_keys(run, _RUN_KEYS, p)
    if "scenario" not in run:
        raise Invalid(p, "missing 'scenario'")
    verdict = run.get("verdict")
    if verdict not in VERDICTS:
        raise Invalid((*p, "verdict"), f"must be one of {', '.join(VERDICTS)}")
    assignment = run.get("assignment") or {}
    _obj(assignment, (*p, "assignment"), "'assignment'")
    for key, value in assignment.items():
        if len(key) > MAX_NAME_CHARS:
            raise Invalid((*p, "assignment", key), f"parameter names are at most {MAX_NAME_CHARS} characters")
        if not isinstance(value, (str, int, float, bool)) or (isinstance(value, float) and not math.isfinite(value)):
            raise Invalid((*p, "assignment", key), "must be a string, number or boolean")
    duration = run.get("duration")
    if duration is not None and (_number(duration, (*p, "duration")) < 0):
        raise Invalid((*p, "duration"), "must not be negative")
    return RunInfo(
        scenario=_str(run["scenario"], (*p, "scenario"), limit=MAX_NAME_CHARS) or "",
        verdict=str(verdict), source=_str(run.get("source"), (*p, "source"), optional=True),
        variant=_str(run.get("variant"), (*p, "variant"), optional=True, limit=MAX_NAME_CHARS),
        assignment=assignment, reason=_str(run.get("reason"), (*p, "reason"), optional=True),
        started=_str(run.get("started"), (*p, "started"), optional=True, limit=64), duration=duration)


def _value_type(item: dict, p: tuple) -> ValueType:
    kind = item.get("type")
    if kind not in KINDS:
        raise Invalid((*p, "type"), f"must be one of {', '.join(KINDS)}")
    members = item.get("members")
    if kind != "enum":
        if members is not None:
            raise Invalid((*p, "members"), "only an enum item has members")
        return ValueType(kind)
    if not isinstance(members, list) or not members:
        raise Invalid((*p, "members"), "an enum item needs its members: a non-empty list of names")
    if len(members) > MAX_MEMBERS:
        raise Invalid((*p, "members"), f"more than {MAX_MEMBERS} members")
    for i, member in enumerate(members):
        _str(member, (*p, "members", i), limit=MAX_NAME_CHARS)
    if len(set(members)) != len(members):
        raise Invalid((*p, "members"), "members must be distinct")
    return ValueType("enum", tuple(members))


def _range(item: dict, value_type: ValueType, p: tuple) -> tuple[tuple[float, float] | None, float | None]:
    value_range, every = item.get("range"), item.get("every")
    if value_range is None:
        if every is not None:
            raise Invalid((*p, "every"), "'every' needs a 'range'")
        return None, None
    if not value_type.numeric:
        raise Invalid((*p, "range"), f"a range needs a numeric item, not {value_type.kind}")
    if item.get("kind") != "cover":
        raise Invalid((*p, "range"), "only cover items have a range")
    if not isinstance(value_range, list) or len(value_range) != 2:
        raise Invalid((*p, "range"), "must be [low, high]")
    low, high = (_number(v, (*p, "range", i)) for i, v in enumerate(value_range))
    if low > high:
        raise Invalid((*p, "range"), f"low {low} is above high {high}")
    if every is not None:
        every = _number(every, (*p, "every"))
        if every <= 0:
            raise Invalid((*p, "every"), "must be above 0")
        if value_type.kind == "int" and not float(every).is_integer():
            raise Invalid((*p, "every"), "an int item's buckets hold whole numbers: 'every' must be whole")
    count = range_bucket_count(value_type.kind, low, high, every or default_every(value_type.kind, low, high))
    if count > MAX_BUCKETS:
        raise Invalid((*p, "every"), f"[{low}..{high}] every {every} makes {count} buckets; at most {MAX_BUCKETS}")
    return (low, high), every


def _item(data: object, index: int) -> tuple[ItemDecl, list, int, list]:
    p: tuple = ("items", index)
    item = _obj(data, p, "an item")
    _unknown_keys(item, _ITEM_KEYS, p)
    name = _str(item.get("name"), (*p, "name"), limit=MAX_NAME_CHARS)
    if not name:
        raise Invalid((*p, "name"), "must not be empty")
    kind = item.get("kind")
    if kind not in ITEM_KINDS:
        raise Invalid((*p, "kind"), f"must be one of {', '.join(ITEM_KINDS)}")
    path = _str(item.get("path", ""), (*p, "path"), limit=MAX_NAME_CHARS) or ""
    components = item.get("items")
    value_type: ValueType | None = None
    value_range, every = None, None
    if components is not None:
        if kind != "cover":
            raise Invalid((*p, "items"), "only a cover item can cross other items")
        if not isinstance(components, list) or len(components) < 2:
            raise Invalid((*p, "items"), "a cross names at least two items")
        for i, component in enumerate(components):
            _str(component, (*p, "items", i), limit=MAX_NAME_CHARS)
        for key in ("type", "members", "unit", "range", "every", "ignore"):
            if key in item:
                raise Invalid((*p, key), f"a cross has no '{key}' (its items have)")
    else:
        value_type = _value_type(item, p)
        value_range, every = _range(item, value_type, p)
    samples = item.get("samples", [])
    if not isinstance(samples, list):
        raise Invalid((*p, "samples"), "must be a list")
    if len(samples) > MAX_SAMPLES_PER_ITEM:
        raise Invalid((*p, "samples"), f"more than {MAX_SAMPLES_PER_ITEM} samples")
    unsampled = item.get("unsampled", [])
    if not isinstance(unsampled, list):
        raise Invalid((*p, "unsampled"), "must be a list")
    if len(unsampled) > MAX_SAMPLES_PER_ITEM:
        raise Invalid((*p, "unsampled"), f"more than {MAX_SAMPLES_PER_ITEM} values")
    ignored = item.get("ignored", 0)
    if type(ignored) is not int or ignored < 0:
        raise Invalid((*p, "ignored"), "must be a whole number of samples, 0 or more")
    decl = ItemDecl(
        name=name, kind=kind, path=path, value_type=value_type,
        unit=_str(item.get("unit"), (*p, "unit"), optional=True, limit=64), range=value_range, every=every,
        event=_str(item.get("event", "end"), (*p, "event"), limit=MAX_NAME_CHARS) or "end",
        text=_str(item.get("text"), (*p, "text"), optional=True),
        ignore=_str(item.get("ignore"), (*p, "ignore"), optional=True),
        items=tuple(components or ()))
    return decl, samples, ignored, unsampled


def _check_samples(decls: list[ItemDecl], samples: list[list], key: str = "samples") -> None:
    by_name = {(d.path, d.name): d for d in decls}
    for index, (decl, values) in enumerate(zip(decls, samples, strict=True)):
        p = ("items", index)
        if decl.is_cross:
            types: list[ValueType] = []
            for i, component in enumerate(decl.items):
                target = by_name.get((decl.path, component))
                if target is None:
                    raise Invalid((*p, "items", i), f"no item '{component}' at path '{decl.path}' in this file")
                if target.kind != "cover" or target.is_cross or target.value_type is None:
                    raise Invalid((*p, "items", i), f"'{component}' is not a cover item (a cross takes cover items)")
                types.append(target.value_type)
            for s, value in enumerate(values):
                if not isinstance(value, list) or len(value) != len(types):
                    raise Invalid((*p, key, s), f"a sample of this cross is a list of {len(types)} values")
                for c, (part, vt) in enumerate(zip(value, types, strict=True)):
                    if not vt.accepts(part):
                        raise Invalid((*p, key, s, c), f"{part!r} is not a {vt.describe()} value")
            continue
        value_type = decl.value_type
        if value_type is None:   # only a cross has none, and crosses were checked above
            continue
        accepts = value_type.accepts
        for s, value in enumerate(values):
            if not accepts(value):
                raise Invalid((*p, key, s), f"{value!r} is not a {value_type.describe()} value")


def validate(doc: object) -> RunCoverage:
    top = _obj(doc, (), COVERAGE_FILE)
    if top.get("format") != FORMAT:
        raise Invalid(("format",) if "format" in top else (), f"not a run coverage file (format must be '{FORMAT}')")
    version = top.get("format_version")
    if type(version) is not int:
        raise Invalid(("format_version",), "must be a whole number")
    if version not in READABLE_VERSIONS:
        raise Invalid(("format_version",), f"format_version {version} is not read by this release "
                                            f"(it reads {' and '.join(map(str, READABLE_VERSIONS))})")
    _unknown_keys(top, {"format", "format_version", "run", "items"}, ())
    run = _run_info(top.get("run"))
    items = top.get("items", [])
    if not isinstance(items, list):
        raise Invalid(("items",), "must be a list")
    if len(items) > MAX_ITEMS:
        raise Invalid(("items",), f"more than {MAX_ITEMS} items")
    decls, samples, ignored, unsampled = [], [], [], []
    seen: dict[str, int] = {}
    for index, data in enumerate(items):
        decl, values, dropped, missed = _item(data, index)
        if decl.full_name in seen:
            raise Invalid(("items", index, "name"),
                           f"item '{decl.full_name}' is declared twice (first as items[{seen[decl.full_name]}])")
        seen[decl.full_name] = index
        decls.append(decl)
        samples.append(values)
        ignored.append(dropped)
        unsampled.append(missed)
    _check_samples(decls, samples)
    _check_samples(decls, unsampled, "unsampled")
    return RunCoverage(run=run, items=tuple(decls), samples=tuple(samples), ignored=tuple(ignored),
                       unsampled=tuple(unsampled) if any(unsampled) else ())
