"""Syntax nodes: the parse tree of an ``.osc`` file as immutable, typed records (see :mod:`coverage_engine.records`).

The parser (``coverage_engine.parse.parser``) builds these in one lark Transformer and puts no meaning
into them: names are not looked up, units are not converted, nothing is evaluated. The resolver
(``coverage_engine.resolve.resolver``) reads them and builds the model. Every node carries a
:class:`~coverage_engine.location.Location`, so every later error can point at the source.
"""

from __future__ import annotations

from coverage_engine.location import Location
from coverage_engine.records import Record, record

# --------------------------------------------------------------------------------------------------
# Names and types


@record
class QualifiedName(Record):
    """A dotted declaration or reference name: ``log``, ``robot.move``, ``osc.helpers`` (parts kept apart)."""

    parts: tuple[str, ...]
    location: Location

    @property
    def dotted(self) -> str:
        return ".".join(self.parts)


@record
class TypeRef(Record):
    """A type as written: ``int``, ``length``, ``position_3d``, ``list of string``."""

    name: QualifiedName
    is_list: bool
    location: Location


# --------------------------------------------------------------------------------------------------
# Expressions


@record
class Literal(Record):
    """A plain literal. ``kind`` is one of ``int``, ``float``, ``bool``, ``string``; ``value`` the Python value.

    Hex integers are already turned into ``int``; strings have their escapes processed.
    """

    kind: str
    value: object
    location: Location


@record
class PhysicalLiteral(Record):
    """A number followed by a unit name: ``3s``, ``-2.0rad``, ``1.0e3m``. ``number`` is int or float as written."""

    number: int | float
    unit: str
    location: Location


@record
class Identifier(Record):
    """A bare name used as a value: a parameter, variable, global, ``it``, a type name (``base_struct``)."""

    name: str
    location: Location


@record
class MemberAccess(Record):
    """``target.member`` (``foo.x``, ``it.x``, ``lib.factorial``)."""

    target: Expression
    member: str
    location: Location


@record
class Argument(Record):
    """One argument of a call or invocation; ``name`` is None for a positional one."""

    name: str | None
    value: Expression
    location: Location


@record
class Call(Record):
    """``callee(args)``: a struct constructor, a method call (``lib.factorial(4)``) or ``elapsed(3s)``."""

    callee: Expression
    arguments: tuple[Argument, ...]
    location: Location


@record
class BinaryOp(Record):
    """``left op right`` with ``op`` one of ``+ - * / % == != < <= > >= and or in =>``."""

    op: str
    left: Expression
    right: Expression
    location: Location


@record
class UnaryOp(Record):
    """``-operand`` or ``not operand``."""

    op: str
    operand: Expression
    location: Location


@record
class Ternary(Record):
    """``condition ? if_true : if_false``."""

    condition: Expression
    if_true: Expression
    if_false: Expression
    location: Location


@record
class ListExpr(Record):
    """``[a, b, c]`` (possibly empty)."""

    items: tuple[Expression, ...]
    location: Location


@record
class RangeExpr(Record):
    """``[low..high]``."""

    low: Expression
    high: Expression
    location: Location


@record
class EnumValueRef(Record):
    """``enum_type!member`` (``enum_type`` may be None when written ``!member``)."""

    enum: str | None
    member: str
    location: Location


@record
class EventRef(Record):
    """``@name`` or ``@actor.name`` in ``wait @test``."""

    path: tuple[str, ...]
    location: Location


Expression = (
    Literal | PhysicalLiteral | Identifier | MemberAccess | Call | BinaryOp | UnaryOp | Ternary |
    ListExpr | RangeExpr | EnumValueRef | EventRef
)


# --------------------------------------------------------------------------------------------------
# Members of declarations


@record
class KeepConstraint(Record):
    """``keep(expr)`` or ``keep(default expr)``; ``location`` spans the whole ``keep(...)``."""

    expression: Expression
    is_default: bool
    location: Location


@record
class ModifierInvocation(Record):
    """A modifier applied by name: ``timeout(60s)`` in a body, ``inverter()`` in a ``with:`` block."""

    name: QualifiedName
    arguments: tuple[Argument, ...]
    location: Location


@record
class CoverageDecl(Record):
    """``cover(...)`` or ``record(...)`` (ASAM OpenSCENARIO DSL 2, coverage): a member of a scenario or a
    ``with:`` block of one of its parameters; ``kind`` is ``"cover"`` or ``"record"``."""

    kind: str
    arguments: tuple[Argument, ...]
    location: Location


@record
class Until(Record):
    """``until @event`` in a behaviour's ``with:`` block (ASAM modifier): the behaviour runs until the event."""

    condition: Expression
    location: Location


WithMember = KeepConstraint | ModifierInvocation | CoverageDecl | Until


@record
class ParameterDecl(Record):
    """``a, b: type = default with: keep(...)`` inside a struct/actor/action/scenario/modifier, or global.

    ``is_global`` is set for ``global`` declarations at file level.
    """

    names: tuple[str, ...]
    type: TypeRef
    default: Expression | None
    with_members: tuple[WithMember, ...]
    location: Location
    is_global: bool = False


@record
class VariableDecl(Record):
    """``var a: type = initial`` (the initial value may be an expression evaluated when the run starts)."""

    names: tuple[str, ...]
    type: TypeRef
    default: Expression | None
    location: Location


@record
class EventDecl(Record):
    """``event name`` (optionally with parameters ``event name(a: int)``)."""

    name: str
    parameters: tuple[MethodParameter, ...]
    location: Location


@record
class MethodParameter(Record):
    """A parameter of a method or event signature: ``n: int = 10``."""

    name: str
    type: TypeRef
    default: Expression | None
    location: Location


@record
class MethodDecl(Record):
    """``def name(params) -> type is external module.function(args)``.

    ``external`` is the dotted Python path (``module.function``); ``external_arguments`` any arguments
    written in that call (usually none).
    """

    name: str
    parameters: tuple[MethodParameter, ...]
    return_type: TypeRef | None
    external: QualifiedName
    external_arguments: tuple[Argument, ...]
    location: Location


@record
class DoDirective(Record):
    """``do <behaviour>``: the body of a scenario or action."""

    behavior: Behavior
    location: Location


# --------------------------------------------------------------------------------------------------
# Behaviours (inside ``do``)


@record
class Composite(Record):
    """``serial:``/``parallel:``/``one_of:`` with members; ``label`` from ``name: serial:``.

    ``members`` holds behaviours and :class:`ModifierInvocation` s written among them (these apply to the
    composite itself, e.g. ``repeat()`` inside a ``serial:``). ``arguments`` are any written after the kind
    (``serial(duration: 3s):``), ``with_members`` those of a trailing ``with:`` block.
    """

    kind: str
    label: str | None
    members: tuple[Behavior | ModifierInvocation, ...]
    arguments: tuple[Argument, ...]
    with_members: tuple[WithMember, ...]
    location: Location


@record
class Invocation(Record):
    """An action or scenario invocation: ``log("x")``, ``robot.move(speed: 1m/s) with: keep(...)``.

    ``name`` is the dotted name as written (``robot.move``: an actor instance or type, then the behaviour).
    """

    label: str | None
    name: QualifiedName
    arguments: tuple[Argument, ...]
    with_members: tuple[WithMember, ...]
    location: Location


@record
class Wait(Record):
    """``wait <expr>``: ``wait elapsed(3s)`` (a :class:`Call` to ``elapsed``), ``wait @event``, ``wait x == 3``."""

    label: str | None
    condition: Expression
    location: Location


@record
class Emit(Record):
    """``emit name`` or ``emit name(args)``; ``end`` and ``fail`` are ordinary names here."""

    label: str | None
    event: str
    arguments: tuple[Argument, ...]
    location: Location


@record
class CallDirective(Record):
    """``call lib.method(args)``: run a method for its effect."""

    label: str | None
    call: Call
    location: Location


Behavior = Composite | Invocation | Wait | Emit | CallDirective


# --------------------------------------------------------------------------------------------------
# Declarations (file level)


@record
class Import(Record):
    """``import osc.helpers`` (``is_file`` False, ``path`` ``osc.helpers``) or ``import "rel/file.osc"``."""

    path: str
    is_file: bool
    location: Location


@record
class PhysicalTypeDecl(Record):
    """``type length is SI(m: 1)``; ``exponents`` maps SI base unit names to integer exponents."""

    name: str
    exponents: tuple[tuple[str, int], ...]
    location: Location


@record
class UnitDecl(Record):
    """``unit cm of length is SI(m: 1, factor: 0.01, offset: 0)``; factor/offset None when not written."""

    name: str
    physical_type: str
    exponents: tuple[tuple[str, int], ...]
    factor: float | None
    offset: float | None
    location: Location


@record
class EnumMember(Record):
    """One member of an enum; ``value`` None when not written."""

    name: str
    value: int | None
    location: Location


@record
class EnumDecl(Record):
    """``enum colour: [red, green = 3, blue]``."""

    name: str
    members: tuple[EnumMember, ...]
    location: Location


Member = (
    ParameterDecl | VariableDecl | EventDecl | MethodDecl | KeepConstraint | ModifierInvocation |
    DoDirective
)


@record
class TypeDecl(Record):
    """A ``struct``, ``actor``, ``action``, ``scenario`` or ``modifier`` declaration (``kind`` says which).

    ``name`` may be qualified (``robot.move`` declares behaviour ``move`` of actor ``robot``); ``parent``
    is the ``inherits`` name. ``members`` keep their written order.
    """

    kind: str
    name: QualifiedName
    parent: QualifiedName | None
    members: tuple[Member, ...]
    location: Location


@record
class Extension(Record):
    """``extend name:`` with members added to an existing type."""

    name: QualifiedName
    members: tuple[Member, ...]
    location: Location


Declaration = PhysicalTypeDecl | UnitDecl | EnumDecl | TypeDecl | Extension | ParameterDecl


@record
class CompilationUnit(Record):
    """One parsed file: its imports and declarations in written order, and its text for error context."""

    file: str
    imports: tuple[Import, ...]
    declarations: tuple[Declaration, ...]
    text: str = ""

    _hidden_in_repr = ("text",)
