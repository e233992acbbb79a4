"""Turn the declarations of all collected files into named types, units and globals.

Two passes: first every name is registered (so declaration order does not matter), then compound
types get their members, parents first. Redeclaring a name is an error at the second declaration.
"""

from __future__ import annotations

from coverage_engine.errors import NameLookupError, ResolveError, UnsupportedFeatureError
from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.resolve.types import (
    PRIMITIVES,
    CompoundType,
    EnumType,
    FieldDecl,
    ListType,
    OscType,
    PhysicalType,
    Unit,
    VarDecl,
)


class Namespace:
    """Everything declared at file level, by name; scenarios of the main file in file order."""

    def __init__(self) -> None:
        self.types: dict[str, OscType] = {}
        self.units: dict[str, Unit] = {}
        self.globals: dict[str, syntax.ParameterDecl] = {}
        self.scenarios: list[CompoundType] = []

    def lookup_type(self, ref: syntax.TypeRef) -> OscType:
        """The type a :class:`~coverage_engine.parse.syntax.TypeRef` names, or an error at its position."""
        name = ref.name.dotted
        base = PRIMITIVES.get(name) or self.types.get(name)
        if base is None:
            raise NameLookupError(f"unknown type '{name}'", ref.location)
        return ListType(base) if ref.is_list else base


_COMPOUND_KINDS = ("struct", "actor", "action", "scenario", "modifier")


def build_namespace(units: list[syntax.CompilationUnit], main: syntax.CompilationUnit) -> Namespace:
    """Register and fill every declaration of ``units``; scenarios of ``main`` are listed in file order."""
    ns = Namespace()
    compounds: list[CompoundType] = []
    extensions: list[syntax.Extension] = []
    for unit in units:
        for decl in unit.declarations:
            if isinstance(decl, syntax.PhysicalTypeDecl):
                _register(ns, decl.name, PhysicalType(decl.name, decl.exponents, decl.location), decl.location)
            elif isinstance(decl, syntax.UnitDecl):
                _register_unit(ns, decl)
            elif isinstance(decl, syntax.EnumDecl):
                _register(ns, decl.name, _enum(decl), decl.location)
            elif isinstance(decl, syntax.TypeDecl):
                ctype = CompoundType(kind=decl.kind, qualified=decl.name.dotted, declaration=decl)
                _register(ns, ctype.qualified, ctype, decl.name.location)
                compounds.append(ctype)
                if decl.kind == "scenario" and unit is main:
                    ns.scenarios.append(ctype)
            elif isinstance(decl, syntax.ParameterDecl):
                for name in decl.names:
                    if name in ns.globals:
                        raise ResolveError(f"global '{name}' is already declared", decl.location)
                    ns.globals[name] = decl
            elif isinstance(decl, syntax.Extension):
                extensions.append(decl)
    filled: set[int] = set()
    for ctype in compounds:
        _fill(ns, ctype, filled, ())
    for ext in extensions:
        target = ns.types.get(ext.name.dotted)
        if not isinstance(target, CompoundType):
            raise NameLookupError(f"cannot extend unknown type '{ext.name.dotted}'", ext.name.location)
        _add_members(ns, target, ext.members)
    return ns


def _register(ns: Namespace, name: str, value: OscType, location: Location) -> None:
    if name.startswith("listof"):
        # The reference implementation rejects such names; refusing them too keeps files portable.
        raise ResolveError(f"type name '{name}': names starting with 'listof' are reserved", location)
    if name in ns.types or name in PRIMITIVES:
        raise ResolveError(f"'{name}' is already declared", location)
    ns.types[name] = value


def _register_unit(ns: Namespace, decl: syntax.UnitDecl) -> None:
    physical = ns.types.get(decl.physical_type)
    if not isinstance(physical, PhysicalType):
        raise NameLookupError(f"unit '{decl.name}': unknown physical type '{decl.physical_type}'", decl.location)
    if dict(decl.exponents) != dict(physical.exponents):
        raise ResolveError(f"unit '{decl.name}' has SI exponents {dict(decl.exponents)}, but "
                           f"'{physical.name}' has {dict(physical.exponents)}", decl.location)
    if decl.name in ns.units:
        raise ResolveError(f"unit '{decl.name}' is already declared", decl.location)
    factor = 1.0 if decl.factor is None else float(decl.factor)
    offset = 0.0 if decl.offset is None else float(decl.offset)
    ns.units[decl.name] = Unit(decl.name, physical, factor, offset, decl.location)


def _enum(decl: syntax.EnumDecl) -> EnumType:
    members: dict[str, int] = {}
    next_value = 0
    for member in decl.members:
        if member.name in members:
            raise ResolveError(f"enum '{decl.name}' has member '{member.name}' twice", member.location)
        value = next_value if member.value is None else member.value
        members[member.name] = value
        next_value = value + 1
    if not members:
        raise ResolveError(f"enum '{decl.name}' has no members", decl.location)
    return EnumType(decl.name, members, decl.location)


def _fill(ns: Namespace, ctype: CompoundType, filled: set[int], stack: tuple[str, ...]) -> None:
    """Give ``ctype`` its parent's members and its own, parents first."""
    if id(ctype) in filled:
        return
    decl = ctype.declaration
    if ctype.qualified in stack:
        raise ResolveError(f"'{ctype.qualified}' inherits from itself", decl.location)
    if decl.parent is not None:
        parent = ns.types.get(decl.parent.dotted)
        if not isinstance(parent, CompoundType):
            raise NameLookupError(f"unknown base type '{decl.parent.dotted}'", decl.parent.location)
        if parent.kind != ctype.kind:
            raise ResolveError(f"{ctype.kind} '{ctype.qualified}' cannot inherit from {parent.kind} "
                               f"'{parent.qualified}'", decl.parent.location)
        _fill(ns, parent, filled, stack + (ctype.qualified,))
        ctype.parent = parent
        ctype.fields = dict(parent.fields)
        ctype.variables = dict(parent.variables)
        ctype.events = dict(parent.events)
        ctype.methods = dict(parent.methods)
        ctype.keeps = list(parent.keeps)
        ctype.modifiers = list(parent.modifiers)
        ctype.coverage = list(parent.coverage)
        ctype.body = parent.body
    filled.add(id(ctype))
    if len(decl.name.parts) > 1:
        _attach_to_actor(ns, ctype)
    _add_members(ns, ctype, decl.members)


def _attach_to_actor(ns: Namespace, ctype: CompoundType) -> None:
    decl = ctype.declaration
    actor_name = ".".join(decl.name.parts[:-1])
    actor = ns.types.get(actor_name)
    if not isinstance(actor, CompoundType) or actor.kind != "actor":
        raise NameLookupError(f"{ctype.kind} '{ctype.qualified}': unknown actor '{actor_name}'", decl.name.location)
    actor.behaviors[decl.name.parts[-1]] = ctype


def _add_members(ns: Namespace, ctype: CompoundType, members: tuple) -> None:
    for member in members:
        if isinstance(member, syntax.ParameterDecl):
            ftype = ns.lookup_type(member.type)
            _check_names(member.names, member.location, "parameter")
            for name in member.names:
                ctype.fields[name] = FieldDecl(name, ftype, member.default, member.with_members, ctype,
                                               member.location)
                for item in member.with_members:
                    if isinstance(item, syntax.CoverageDecl):
                        _check_coverage_owner(ctype, item)
                        ctype.coverage.append((item, name))
        elif isinstance(member, syntax.VariableDecl):
            vtype = ns.lookup_type(member.type)
            _check_names(member.names, member.location, "variable")
            for name in member.names:
                ctype.variables[name] = VarDecl(name, vtype, member.default, ctype, member.location)
        elif isinstance(member, syntax.EventDecl):
            if member.name in ("end", "fail", "finish"):
                raise ResolveError(f"'{member.name}' is a built-in event of every scenario; declare an event with "
                                   "another name", member.location)
            ctype.events[member.name] = member
        elif isinstance(member, syntax.MethodDecl):
            ctype.methods[member.name] = member
        elif isinstance(member, syntax.KeepConstraint):
            ctype.keeps.append(member)
        elif isinstance(member, syntax.ModifierInvocation):
            ctype.modifiers.append(member)
        elif isinstance(member, syntax.CoverageDecl):
            _check_coverage_owner(ctype, member)
            ctype.coverage.append((member, None))
        elif isinstance(member, syntax.DoDirective):
            if ctype.kind not in ("scenario", "action"):
                raise ResolveError(f"a {ctype.kind} cannot have a 'do' body", member.location)
            if ctype.kind == "action":
                raise UnsupportedFeatureError("not supported: 'do' in an action declaration", member.location)
            if ctype.body is not None and ctype.body.location.file == member.location.file \
                    and any(m is ctype.body for m in members):
                raise ResolveError(f"{ctype.kind} '{ctype.name}' already has a 'do' body "
                                   f"(line {ctype.body.location.line})", member.location)
            ctype.body = member


def _check_coverage_owner(ctype: CompoundType, decl: syntax.CoverageDecl) -> None:
    """cover()/record() are sampled per scenario run; in an actor, struct or action they are refused (for now)."""
    if ctype.kind != "scenario":
        raise UnsupportedFeatureError(f"not supported: {decl.kind}() in {ctype.kind} '{ctype.qualified}' (declare it "
                                      f"in the scenario, with expression: naming the {ctype.kind}'s member)",
                                      decl.location)


#: Keywords of the ASAM OpenSCENARIO DSL 2 grammar that look like names: the SI base unit names and
#: ``factor`` (unit declarations). A member cannot be called one of them (``s_count``, ``mol3`` are fine).
RESERVED_NAMES = frozenset({"kg", "m", "s", "A", "K", "mol", "cd", "rad", "factor"})


def _check_names(names: tuple[str, ...], location: Location, what: str) -> None:
    for name in names:
        if name in RESERVED_NAMES:
            raise ResolveError(f"'{name}' is a keyword of the language (an SI base unit name or 'factor'), not a "
                               f"{what} name; choose another name (e.g. '{name}_value')", location)
