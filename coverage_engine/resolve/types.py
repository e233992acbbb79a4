"""The resolver's type objects: primitive, physical, enum, compound (struct/actor/…) and list types.

Types know their zero value and how to check and convert a value given to them (a literal, a folded
expression or a YAML override). They carry no syntax nodes except the declaration they came from.
"""

from __future__ import annotations

from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.resolve.model import EnumValue


class OscType:
    """Base of every type; ``name`` as users write it, ``kind`` what sort of type it is."""

    __slots__ = ()
    name: str
    kind: str

    def __str__(self) -> str:
        return self.name


class PrimitiveType(OscType):
    """``int``, ``uint``, ``float``, ``bool``, ``string``."""

    __slots__ = ("name", "kind")

    def __init__(self, name: str) -> None:
        self.name, self.kind = name, "primitive"

    def __repr__(self) -> str:
        return f"PrimitiveType({self.name!r})"


class PhysicalType(OscType):
    """A quantity with SI exponents (``length``: m¹); values are floats in the SI base unit."""

    __slots__ = ("name", "kind", "exponents", "location")

    def __init__(self, name: str, exponents: tuple[tuple[str, int], ...],
                 location: Location | None = None) -> None:
        self.name, self.kind, self.exponents, self.location = name, "physical", exponents, location

    def __repr__(self) -> str:
        return f"PhysicalType({self.name!r}, {self.exponents!r})"


class Unit:
    """A unit of a physical type: ``value_si = number * factor + offset``."""

    __slots__ = ("name", "physical", "factor", "offset", "location")

    def __init__(self, name: str, physical: PhysicalType, factor: float, offset: float,
                 location: Location | None = None) -> None:
        self.name, self.physical, self.factor, self.offset, self.location = name, physical, factor, offset, location


class EnumType(OscType):
    """An enum with its members (name → number) in declaration order."""

    __slots__ = ("name", "kind", "members", "location")

    def __init__(self, name: str, members: dict[str, int], location: Location | None = None) -> None:
        self.name, self.kind, self.members, self.location = name, "enum", members, location

    def value(self, member: str) -> EnumValue:
        return EnumValue(member, self.members[member])


class ListType(OscType):
    """``list of element``."""

    __slots__ = ("element", "kind")

    def __init__(self, element: OscType) -> None:
        self.element, self.kind = element, "list"

    @property
    def name(self) -> str:  # type: ignore[override]
        return f"list of {self.element.name}"


class FieldDecl:
    """A parameter member of a compound type (``x: length = 1m``)."""

    __slots__ = ("name", "type", "default", "with_members", "owner", "location")

    def __init__(self, name: str, type_: OscType, default: syntax.Expression | None, with_members: tuple,
                 owner: CompoundType, location: Location) -> None:
        self.name, self.type, self.default, self.with_members = name, type_, default, with_members
        self.owner, self.location = owner, location


class VarDecl:
    """A ``var`` member of a compound type."""

    __slots__ = ("name", "type", "initial", "owner", "location")

    def __init__(self, name: str, type_: OscType, initial: syntax.Expression | None, owner: CompoundType,
                 location: Location) -> None:
        self.name, self.type, self.initial, self.owner, self.location = name, type_, initial, owner, location


class CompoundType(OscType):
    """A struct, actor, action, scenario or modifier; members are merged with the parent's, parent first.

    ``qualified`` is the declared name (``robot.move``), also its ``name``. Members are filled in by
    :mod:`coverage_engine.resolve.namespace` after every name is registered.
    """

    def __init__(self, kind: str, qualified: str, declaration: syntax.TypeDecl,
                 parent: CompoundType | None = None) -> None:
        self.kind, self.qualified, self.declaration, self.parent = kind, qualified, declaration, parent
        self.fields: dict[str, FieldDecl] = {}
        self.variables: dict[str, VarDecl] = {}
        self.events: dict[str, syntax.EventDecl] = {}
        self.methods: dict[str, syntax.MethodDecl] = {}
        self.keeps: list[syntax.KeepConstraint] = []
        self.modifiers: list[syntax.ModifierInvocation] = []
        #: cover()/record() members, each with the parameter whose ``with:`` block holds it (None: a member)
        self.coverage: list[tuple[syntax.CoverageDecl, str | None]] = []
        self.body: syntax.DoDirective | None = None
        self.behaviors: dict[str, CompoundType] = {}

    @property
    def name(self) -> str:  # type: ignore[override]
        return self.qualified

    def __repr__(self) -> str:
        return f"CompoundType({self.kind} {self.qualified})"

    def ancestry(self) -> list[CompoundType]:
        """This type and its parents, nearest first."""
        chain: list[CompoundType] = []
        node: CompoundType | None = self
        while node is not None:
            chain.append(node)
            node = node.parent
        return chain

    def is_a(self, other: CompoundType) -> bool:
        return any(t is other for t in self.ancestry())


INT = PrimitiveType("int")
UINT = PrimitiveType("uint")
FLOAT = PrimitiveType("float")
BOOL = PrimitiveType("bool")
STRING = PrimitiveType("string")
#: The type of ``it``/events/``elapsed(...)`` calls and of things no value is expected from.
ANY = PrimitiveType("any")

PRIMITIVES: dict[str, PrimitiveType] = {t.name: t for t in (INT, UINT, FLOAT, BOOL, STRING)}


def is_numeric(t: OscType) -> bool:
    """True for ``int``, ``uint`` and ``float`` (physical types are not plain numbers)."""
    return t is INT or t is UINT or t is FLOAT


def zero_value(t: OscType) -> object:
    """The value of a parameter of type ``t`` that has no default and no given value."""
    if t is INT or t is UINT:
        return 0
    if t is FLOAT or isinstance(t, PhysicalType):
        return 0.0
    if t is BOOL:
        return False
    if t is STRING:
        return ""
    if isinstance(t, ListType):
        return []
    if isinstance(t, EnumType):
        first = next(iter(t.members))
        return t.value(first)
    return None


class ConversionError(Exception):
    """A value does not fit a type; the message says why (the caller adds the location)."""


def convert(value: object, t: OscType, where: str = "value") -> object:
    """Check ``value`` (a plain Python value) against ``t`` and convert it (int→float, number→string…).

    Struct values must already be dicts of converted members; this checks the shape only for
    primitives, physical values, enums and lists. Used for folded expressions and YAML overrides.
    """
    if t is ANY:
        return value
    if t is STRING:
        if isinstance(value, str):
            return value
        if isinstance(value, bool):
            raise ConversionError(f"{where}: expected string, got bool")
        if isinstance(value, (int, float)):
            return str(value)
        raise ConversionError(f"{where}: expected string, got {_kind(value)}")
    if t is BOOL:
        if isinstance(value, bool):
            return value
        raise ConversionError(f"{where}: expected bool, got {_kind(value)}")
    if t is INT or t is UINT:
        if isinstance(value, int) and not isinstance(value, bool):
            if t is UINT and value < 0:
                raise ConversionError(f"{where}: expected uint, got negative {value}")
            return value
        raise ConversionError(f"{where}: expected {t.name}, got {_kind(value)}")
    if t is FLOAT or isinstance(t, PhysicalType):
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            # a physical value keeps the kind it was written with (``2s`` is 2, ``100ms`` 0.1), as it prints
            return float(value) if t is FLOAT else value
        raise ConversionError(f"{where}: expected {t.name}, got {_kind(value)}")
    if isinstance(t, EnumType):
        if isinstance(value, EnumValue) and value.name in t.members:
            return value
        if isinstance(value, str) and value in t.members:
            return t.value(value)
        raise ConversionError(f"{where}: expected a member of enum {t.name} ({', '.join(t.members)}), "
                              f"got {value!r}")
    if isinstance(t, ListType):
        if not isinstance(value, list):
            raise ConversionError(f"{where}: expected {t.name}, got {_kind(value)}")
        return [convert(v, t.element, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(t, CompoundType):
        if isinstance(value, dict):
            return value
        raise ConversionError(f"{where}: expected {t.name}, got {_kind(value)}")
    return value


def _kind(value: object) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "int"
    if isinstance(value, float):
        return "float"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list):
        return "list"
    if isinstance(value, dict):
        return "struct"
    if isinstance(value, EnumValue):
        return "enum value"
    return type(value).__name__
