"""The coverage plan (``--plan plan.yaml``): weights of items and hit targets of their buckets.

::

    at_least: 1            # default: hits a bucket needs to count as covered
    weight: 1              # default weight of an item in the overall grade
    items:
      cut_in.speed:        # an item's full name …
        at_least: 3
        weight: 2
      "input:*":           # … or a pattern (* and ?), matched in the order written
        weight: 0.5
      "input:* x *":
        weight: 0          # shown, but not part of the overall grade

An exact name wins over patterns; of several patterns the first that matches applies. Errors point
at the key or value in the file (``plan.yaml:4:18: error: …``).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from fnmatch import fnmatchcase
from typing import TYPE_CHECKING

from coverage_engine.coverage.errors import PlanError
from coverage_engine.location import Location

if TYPE_CHECKING:      # (read at run time only by a plan's parse: a batch's report needs no YAML)
    import yaml

#: Largest plan file read.
MAX_PLAN_BYTES = 1024 * 1024

_TOP_KEYS = ("at_least", "weight", "items")
_ITEM_KEYS = ("at_least", "weight")


@dataclass(frozen=True)
class ItemPlan:
    """What the plan says about one item."""

    weight: float = 1.0
    at_least: int = 1


@dataclass(frozen=True)
class CoveragePlan:
    """Defaults, exact entries and patterns; :meth:`for_item` answers per item."""

    default: ItemPlan = ItemPlan()
    exact: dict[str, ItemPlan] = field(default_factory=dict)
    patterns: tuple[tuple[str, ItemPlan], ...] = ()
    file: str | None = None

    def for_item(self, name: str) -> ItemPlan:
        found = self.exact.get(name)
        if found is not None:
            return found
        for pattern, entry in self.patterns:
            if fnmatchcase(name, pattern):
                return entry
        return self.default

    def names(self, name: str) -> bool:
        """Whether an entry of the plan (its exact name or a pattern) is about item ``name``."""
        return name in self.exact or any(fnmatchcase(name, pattern) for pattern, _ in self.patterns)

    def unmatched(self, names: list[str]) -> list[str]:
        """Entries of the plan that name no item (likely typos), in file order."""
        known = set(names)
        out = [name for name in self.exact if name not in known]
        out += [pattern for pattern, _ in self.patterns if not any(fnmatchcase(n, pattern) for n in names)]
        return out


def _error(file: str, node: yaml.Node, message: str, text: str) -> PlanError:
    mark = node.start_mark
    lines = text.splitlines()
    source = lines[mark.line] if mark.line < len(lines) else None
    return PlanError(message, Location.at(file, mark.line + 1, mark.column + 1), source_line=source)


def _mapping(file: str, node: yaml.Node, what: str, allowed: tuple[str, ...], text: str) -> dict:
    import yaml

    if not isinstance(node, yaml.MappingNode):
        raise _error(file, node, f"{what} must be a mapping", text)
    out: dict[str, tuple[yaml.Node, yaml.Node]] = {}
    for key, value in node.value:
        if not isinstance(key, yaml.ScalarNode):
            raise _error(file, key, "keys must be plain names", text)
        name = key.value
        if allowed and name not in allowed:
            raise _error(file, key, f"unknown key '{name}' in {what} (known: {', '.join(allowed)})", text)
        if name in out:
            raise _error(file, key, f"'{name}' appears twice in {what}", text)
        out[name] = (key, value)
    return out


def _scalar(file: str, node: yaml.Node, text: str) -> object:
    import yaml

    if not isinstance(node, yaml.ScalarNode):
        raise _error(file, node, "must be a number", text)
    return yaml.safe_load(node.value) if not node.style else node.value   # plain: None (Python), "" (libyaml)


def _weight(file: str, node: yaml.Node, text: str) -> float:
    value = _scalar(file, node, text)
    if (type(value) is int or type(value) is float) and math.isfinite(value) and value >= 0:
        return float(value)
    raise _error(file, node, f"weight must be a number, 0 or more (got {node.value!r})", text)


def _at_least(file: str, node: yaml.Node, text: str) -> int:
    value = _scalar(file, node, text)
    if type(value) is not int or value < 1 or value > 10**9:
        raise _error(file, node, f"at_least must be a whole number of hits, 1 or more (got {node.value!r})", text)
    return value


def _entry(file: str, node: yaml.Node, default: ItemPlan, text: str, what: str) -> ItemPlan:
    fields = _mapping(file, node, what, _ITEM_KEYS, text)
    weight = _weight(file, fields["weight"][1], text) if "weight" in fields else default.weight
    at_least = _at_least(file, fields["at_least"][1], text) if "at_least" in fields else default.at_least
    return ItemPlan(weight=weight, at_least=at_least)


def parse_plan(text: str, file: str = "plan.yaml") -> CoveragePlan:
    """Parse and check a plan's text."""
    import yaml

    from coverage_engine.yaml_bounds import YamlLimitError, compose_bounded

    try:
        root = compose_bounded(text)
    except YamlLimitError as exc:
        raise PlanError(str(exc), Location.at(file, exc.line, exc.column)) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = Location.at(file, mark.line + 1, mark.column + 1) if mark else Location.whole_file(file)
        raise PlanError(f"not valid YAML: {exc.problem or exc}", where) from None
    except yaml.YAMLError as exc:
        raise PlanError(f"not valid YAML: {exc}", Location.whole_file(file)) from None
    if root is None:
        return CoveragePlan(file=file)
    top = _mapping(file, root, "the plan", _TOP_KEYS, text)
    default = ItemPlan(
        weight=_weight(file, top["weight"][1], text) if "weight" in top else 1.0,
        at_least=_at_least(file, top["at_least"][1], text) if "at_least" in top else 1)
    exact: dict[str, ItemPlan] = {}
    patterns: list[tuple[str, ItemPlan]] = []
    if "items" in top:
        items_node = top["items"][1]
        if isinstance(items_node, yaml.ScalarNode) and items_node.value in ("", "~", "null"):
            items: dict = {}
        else:
            items = _mapping(file, items_node, "'items'", (), text)
        for name, (_key, value) in items.items():
            entry = _entry(file, value, default, text, f"item '{name}'")
            if any(ch in name for ch in "*?["):
                patterns.append((name, entry))
            else:
                exact[name] = entry
    return CoveragePlan(default=default, exact=exact, patterns=tuple(patterns), file=file)


def read_plan(path: str | os.PathLike[str]) -> CoveragePlan:
    """Read the plan file at ``path`` (at most :data:`MAX_PLAN_BYTES`)."""
    name = os.fspath(path)
    try:
        with open(name, "rb") as handle:
            data = handle.read(MAX_PLAN_BYTES + 1)
    except OSError as exc:
        raise PlanError(f"cannot read the plan: {exc.strerror or exc}", Location.whole_file(name)) from None
    if len(data) > MAX_PLAN_BYTES:
        raise PlanError(f"the plan is larger than {MAX_PLAN_BYTES} bytes", Location.whole_file(name))
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise PlanError("the plan is not UTF-8 text", Location.whole_file(name)) from None
    return parse_plan(text, name)
