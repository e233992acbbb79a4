"""Sample a running scenario's ``cover()`` and ``record()`` items, and write the run's ``coverage.json``.

When an item is sampled is its event's business:

- ``end`` (the default): once, when the scenario ends *and passed* — a failed run has no ``end`` event,
  as the specification says; its end-items' values at the failure are kept apart as ``unsampled``;
- ``finish`` (our name for it, as in Foretify): once at the end of every run, passed or failed, so the
  KPIs of failing runs are kept;
- a scenario event: each time the scenario emits it.

A sample reads the item's expression from the run's variables (values in SI base units are turned
into the item's unit) and goes through :class:`~coverage_engine.coverage.run_file.RunCoverageBuilder`,
which checks everything once when the file is built. A cross samples the current values of its
items together. The file lands in the run's output folder, atomically; a run without an output folder
samples nothing (there is nowhere to keep it).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from coverage_engine.coverage.run_file import ItemSamples, RunCoverageBuilder, write_run_coverage
from coverage_engine.coverage.values import ValueType
from coverage_engine.resolve.evaluate import evaluate
from coverage_engine.resolve.model import CoverageItem, Scenario, VariableRef
from executor.runtime.planned_runs import RunOrigin

#: JUnit property values longer than this are cut (a record item sampled every tick).
PROPERTY_CHARS = 200


class CoverageSampler:
    """The items of one run, their samplers, and when each is sampled."""

    def __init__(self, scenario: Scenario, variables: dict[str, object], *, run_name: str | None = None,
                 origin: RunOrigin | None = None) -> None:
        self.scenario = scenario
        self.variables = variables
        self.run_name = run_name or scenario.name
        # a run of one parameter document is named after it; else a variant is its .sce file's name
        variant = self.run_name if self.run_name != scenario.name else origin.variant if origin else None
        self.builder = RunCoverageBuilder(scenario.name, source=origin.source if origin else None, variant=variant,
                                          assignment=origin.assignment if origin else None)
        self._items: dict[str, tuple[CoverageItem, ItemSamples]] = {}
        self._by_event: dict[str, list[tuple[CoverageItem, ItemSamples]]] = {}
        declared = {item.name: item for item in scenario.coverage}
        for item in scenario.coverage:
            samples = self._declare(item)
            self._items[item.name] = (item, samples)
            self._by_event.setdefault(item.event, []).append((item, samples))
        self._parts = {item.name: tuple(declared[name] for name in item.items) for item in scenario.coverage
                       if item.items}
        self._getters = {item.name: _getter(item, variables) for item in scenario.coverage if not item.items}

    def _declare(self, item: CoverageItem) -> ItemSamples:
        path, builder = self.scenario.name, self.builder
        if item.items:
            return builder.cross(item.name, item.items, path=path, event=item.event, text=item.text)
        value_type = ValueType(item.value_kind, item.members)
        if item.kind == "record":
            return builder.record(item.name, value_type=value_type, path=path, unit=item.unit, event=item.event,
                                  text=item.text)
        return builder.cover(item.name, value_type=value_type, path=path, unit=item.unit, range=item.range,
                             every=item.every, event=item.event, text=item.text, ignore=item.ignore_text)

    def on_event(self, event: str) -> None:
        """The scenario emitted ``event``: sample the items waiting for it."""
        for item, samples in self._by_event.get(event, ()):
            self._sample(item, samples)

    def finish(self, passed: bool) -> None:
        """The run ended: sample the ``end`` items if it passed, the ``finish`` items in any case.

        A failed run's ``end`` never comes; its ``end`` items keep the values they had at the failure as
        *unsampled* (not samples: the report shows where failing runs were instead of calling it a hole).
        """
        if passed:
            self.on_event("end")
        else:
            for item, samples in self._by_event.get("end", ()):
                self._note_failure(item, samples)
        self.on_event("finish")

    def _note_failure(self, item: CoverageItem, samples: ItemSamples) -> None:
        try:
            if item.ignore is not None and evaluate(item.ignore, self.variables) is True:
                return
            if item.items:
                value: object = [self._value(part) for part in self._parts[item.name]]
            else:
                value = self._value(item)
        except Exception:  # noqa: BLE001 - a value that cannot be read at the failure is simply not noted
            return
        samples.unsampled.append(value)

    def _sample(self, item: CoverageItem, samples: ItemSamples) -> None:
        if item.ignore is not None and evaluate(item.ignore, self.variables) is True:
            samples.drop()
            return
        if item.items:
            samples.add([self._value(part) for part in self._parts[item.name]])
        else:
            samples.add(self._value(item))

    def _value(self, item: CoverageItem) -> object:
        value = self._getters[item.name]()
        kind = item.value_kind
        if kind == "enum":
            return value[0] if isinstance(value, tuple) else str(value)
        if kind == "float":
            number = float(value)  # type: ignore[arg-type]
            if item.unit is not None:
                number = (number - item.unit_offset) / item.unit_factor
            return number
        return value

    def properties(self) -> dict[str, str]:
        """One JUnit property per item sampled: ``coverage.<run>.<item>`` = its samples."""
        result = {}
        for name, (_item, samples) in self._items.items():
            if samples.values:
                result[f"coverage.{self.run_name}.{name}"] = _samples_text(samples.values)
        return result

    def write(self, output_dir: str, verdict: str, reason: str | None, duration: float) -> str:
        """Write ``coverage.json`` into ``output_dir``; returns its path."""
        run = self.builder.build(verdict, reason or None, duration=duration)
        return str(write_run_coverage(output_dir, run))


def _getter(item: CoverageItem, variables: dict[str, object]) -> Callable[[], object]:
    """A function giving the item's current value: a plain variable is read directly (sampling every tick
    of a long run must cost next to nothing), anything else goes through the model's evaluator."""
    expression = item.expression
    assert expression is not None
    if isinstance(expression, VariableRef):
        key = expression.variable.key
        return lambda: variables[key]
    return lambda: evaluate(expression, variables)


def _samples_text(values: Sequence[object]) -> str:
    text = ", ".join(_one(v) for v in values)
    return text if len(text) <= PROPERTY_CHARS else text[:PROPERTY_CHARS - 1] + "…"


def _one(value: object) -> str:
    if isinstance(value, list):
        return "(" + ", ".join(_one(v) for v in value) + ")"
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)

