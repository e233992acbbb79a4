"""The resolved model: what the resolver hands to the runtime, the variation generator and ``-l``.

Everything here is plain data with names already looked up, types checked, defaults filled in and
physical values in SI base units. Values that can only be known while a scenario runs (variables,
external method results) stay as small :data:`Expr` trees that :mod:`coverage_engine.resolve.evaluate`
computes against the current variable values; everything else is folded to :class:`Const`.

Value representation (also what ``log`` prints, as Python ``repr``/``str``):
``int``, ``float`` (every physical value: SI base unit), ``bool``, ``str``, ``list``,
``dict`` for struct/actor instances (members in declaration order, inherited ones first) and
:class:`EnumValue` (prints as ``('name', value)``).
"""

from __future__ import annotations

from coverage_engine.location import Location
from coverage_engine.records import Record, record


class EnumValue(tuple):
    """An enum member: a ``(name, numeric value)`` tuple, so it prints the way users expect."""

    __slots__ = ()

    def __new__(cls, name: str, value: int) -> EnumValue:
        return super().__new__(cls, (name, value))

    @property
    def name(self) -> str:
        return self[0]

    @property
    def value(self) -> int:
        return self[1]


# --------------------------------------------------------------------------------------------------
# Run-time expressions


@record
class Const(Record):
    """A value known before the run."""

    value: object


@record
class Variable(Record):
    """A ``var``: ``key`` is unique within its scenario (``my_actor.my_struct.count``); ``initial`` its start value.

    ``type_name`` is the declared type (``int``, ``float``, ``string``, ``bool``, a physical type or a
    struct name); ``increment``/``decrement`` need a numeric one.
    """

    key: str
    type_name: str
    initial: Expr
    location: Location


@record
class VariableRef(Record):
    """The current value of a variable."""

    variable: Variable


@record
class FieldOf(Record):
    """A member of a struct value computed at run time: ``target[name]``."""

    target: Expr
    name: str


@record
class ExternalMethod(Record):
    """A ``def … is external module.function()`` signature.

    ``parameters`` are ``(name, type_name, default Expr or None)`` in order. The Python function is
    imported when first called (late), with the working directory and the scenario's directory importable.
    """

    name: str
    module: str
    function: str
    parameters: tuple[tuple[str, str, Expr | None], ...]
    return_type: str | None
    location: Location


@record
class ExternalCall(Record):
    """A call of an external method; ``arguments`` map every parameter name to its value expression."""

    method: ExternalMethod
    arguments: tuple[tuple[str, Expr], ...]
    location: Location


@record
class Operation(Record):
    """An operator applied at run time. ``op``: ``+ - * / % == != < <= > >= and or not neg in``."""

    op: str
    operands: tuple[Expr, ...]
    location: Location


@record
class MakeList(Record):
    """A list whose items are computed at run time."""

    items: tuple[Expr, ...]


@record
class MakeStruct(Record):
    """A struct instance whose members are computed at run time (``dict`` in member order)."""

    type_name: str
    members: tuple[tuple[str, Expr], ...]


Expr = Const | VariableRef | FieldOf | ExternalCall | Operation | MakeList | MakeStruct


# --------------------------------------------------------------------------------------------------
# Behaviours


@record
class Composite(Record):
    """``serial``, ``parallel`` or ``one_of`` (``kind``); ``name`` is the label or the kind."""

    kind: str
    name: str
    children: tuple[Behavior, ...]
    location: Location


@record
class ActionCall(Record):
    """An action invocation ready to run.

    ``action`` is the declared (qualified) name, e.g. ``log`` or ``robot.move``; ``plugin_names`` the
    entry-point names to try in order in group ``scenario_execution.actions`` (the action itself first,
    then the actions it inherits from). ``arguments`` holds every declared parameter in declaration order
    (defaults filled, keeps applied); parameters without a value are absent. ``actor`` is the associated
    actor instance for ``actor.action`` invocations, else None.
    """

    action: str
    plugin_names: tuple[str, ...]
    name: str
    arguments: tuple[tuple[str, Expr], ...]
    actor: Expr | None
    location: Location
    #: Whether ``name`` is a label the scenario wrote (``ready: run_process(...)``), not the action's own name.
    labelled: bool = False


@record
class WaitElapsed(Record):
    """``wait elapsed(duration)``: duration in seconds (simulation time when a simulation runs)."""

    name: str
    duration: Expr
    location: Location


@record
class WaitCondition(Record):
    """``wait <condition>``: running until the condition is true."""

    name: str
    condition: Expr
    location: Location


@record
class WaitEvent(Record):
    """``wait @event``: running until the event (by key) has been emitted."""

    name: str
    event: str
    location: Location


@record
class EmitEvent(Record):
    """``emit event``. The keys ``end`` and ``fail`` end the scenario at once with success or failure."""

    name: str
    event: str
    location: Location


@record
class CallMethod(Record):
    """``call …``: evaluate an expression for its effect."""

    name: str
    call: Expr
    location: Location


@record
class Modified(Record):
    """A modifier wrapped around a behaviour: ``timeout``, ``repeat``, ``retry``, ``inverter``,
    ``failure_is_running`` … ``success_is_running``.

    ``arguments`` are the modifier's declared parameters with constant values (``duration`` in seconds,
    ``count`` as int). Several modifiers on one behaviour nest in the order written: the first written is
    the outermost.
    """

    modifier: str
    arguments: tuple[tuple[str, object], ...]
    child: Behavior
    location: Location


Behavior = (
    Composite | ActionCall | WaitElapsed | WaitCondition | WaitEvent | EmitEvent | CallMethod |
    Modified
)


# --------------------------------------------------------------------------------------------------
# Scenarios


@record
class Parameter(Record):
    """A scenario-level parameter with its resolved value (structs as dicts) and declared type name.

    ``overridable`` is False for parameters a YAML document may not set (actors, defaults that refer
    to other names); such parameters are left out of the parameter-file template.
    """

    name: str
    type_name: str
    value: object
    location: Location
    overridable: bool = True


@record
class CoverageItem(Record):
    """A ``cover()`` or ``record()`` item of a scenario, ready to sample.

    ``expression`` gives the value (in SI base units for a physical type; ``unit_factor`` and
    ``unit_offset`` turn it into ``unit``); None for a cross, whose ``items`` name cover items of the
    same scenario. ``value_kind`` is ``int``, ``float``, ``bool``, ``string`` or ``enum`` (``members``
    then lists its members). ``event`` is when it is sampled: ``end`` (only when the scenario passes),
    ``finish`` (every run, passed or failed) or a scenario event's name. A sample for which
    ``ignore`` is true is counted as ignored.
    """

    kind: str
    name: str
    expression: Expr | None
    value_kind: str
    members: tuple[str, ...]
    unit: str | None
    unit_factor: float
    unit_offset: float
    range: tuple[float, float] | None
    every: float | None
    event: str
    text: str | None
    ignore: Expr | None
    ignore_text: str | None
    items: tuple[str, ...]
    location: Location


@record
class Scenario(Record):
    """One scenario ready to run. ``body`` already includes the scenario-level modifiers (``timeout(60s)``)."""

    name: str
    file: str
    parameters: tuple[Parameter, ...]
    variables: tuple[Variable, ...]
    events: tuple[str, ...]
    body: Behavior | None
    location: Location
    coverage: tuple[CoverageItem, ...] = ()

    def parameter_values(self) -> dict[str, object]:
        """Parameter name → value, as injected into a simulation's ``reset``."""
        return {p.name: p.value for p in self.parameters}


@record
class ScenarioFile(Record):
    """A resolved file: its scenarios in file order, and where it came from.

    ``search_paths`` are the folders the file's relative imports and user modules (external methods)
    are found in: the file's own folder, or for a ``.sce`` the folder of the ``.osc`` it came from.
    """

    path: str
    scenarios: tuple[Scenario, ...]
    search_paths: tuple[str, ...] = ()
