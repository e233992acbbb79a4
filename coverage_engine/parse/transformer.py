"""The one lark Transformer that turns ``grammar.lark`` matches into :mod:`coverage_engine.parse.syntax` nodes.

It runs inside the LALR parser (no intermediate parse tree) with every token kept, so each rule
sees its first and last token and computes its own :class:`~coverage_engine.parse.Location` --
exact to the character, which the variation generator needs to cut and replace source. No
semantics here: nothing is looked up, converted or evaluated. A rule reads its parts by name, never by
position (:mod:`~coverage_engine.parse.parts`). Constructs the grammar accepts only
so they can be refused by name (``cover``, ``on @event``, ``sample`` …) raise
:class:`UnsupportedFeatureError` at their position.
"""

from __future__ import annotations

from typing import NoReturn

from coverage_engine.errors import OscSyntaxError
from coverage_engine.location import Location
from coverage_engine.parse import syntax as s
from coverage_engine.parse.parts import (
    Default,
    ExternalImpl,
    Inherits,
    Marker,
    MethodParams,
    SiArgument,
    SiArguments,
    SignedNumber,
    WithBlock,
    arguments_of,
    built,
    maybe_node,
    maybe_token,
    node,
    nodes,
    token,
    tokens,
)
from coverage_engine.parse.transformer_expr import BehaviorExpressionRules, Children

#: Member statements that declare coverage items rather than apply a modifier.
COVERAGE_MEMBERS = ("cover", "record")


class SyntaxBuilder(BehaviorExpressionRules):
    """Callbacks for the declaration rules; expressions and behaviours come from the mixin."""

    # ------------------------------------------------------------------ file level

    def start(self, children: Children) -> s.CompilationUnit:
        imports = nodes(children, s.Import)
        decls = tuple(c for c in built(children) if not isinstance(c, s.Import))
        return s.CompilationUnit(self.file, imports, decls, self.text)

    def import_stmt(self, children: Children) -> s.Import:
        path = maybe_token(children, "STRING")
        if path is not None:
            from coverage_engine.parse.strings import unescape_string

            return s.Import(unescape_string(str(path)), True, self.loc(children))
        return s.Import(node(children, s.QualifiedName).dotted, False, self.loc(children))

    def qualified_name(self, children: Children) -> s.QualifiedName:
        if len(children) == 1:
            (only,) = children
            return s.QualifiedName((self.name(only),), self.tloc(only))
        return s.QualifiedName(tuple(self.name(t) for t in tokens(children, "NAME")), self.loc(children))

    def namespace_decl(self, children: Children) -> NoReturn:
        raise self.unsupported("namespaces", token(children, "NAMESPACE"))

    def physical_type_decl(self, children: Children) -> s.PhysicalTypeDecl:
        exps = []
        for arg in node(children, SiArguments).items:
            if arg.name in ("factor", "offset"):
                raise OscSyntaxError(f"'{arg.name}' belongs in a unit declaration, not a type", arg.location,
                                     self.source_line(arg.location.line))
            exps.append((arg.name, self.exponent(arg.value, arg.location)))
        return s.PhysicalTypeDecl(self.name(token(children, "NAME")), tuple(exps), self.loc(children))

    def unit_decl(self, children: Children) -> s.UnitDecl:
        name, type_name = tokens(children, "NAME")
        exps, factor, offset = [], None, None
        for arg in node(children, SiArguments).items:
            if arg.name == "factor":
                factor = float(arg.value)
            elif arg.name == "offset":
                offset = float(arg.value)
            else:
                exps.append((arg.name, self.exponent(arg.value, arg.location)))
        return s.UnitDecl(self.name(name), self.name(type_name), tuple(exps), factor, offset,
                          self.loc(children))

    def exponent(self, value: int | float, loc: Location) -> int:
        if not isinstance(value, int):
            raise OscSyntaxError("an SI exponent must be an integer", loc, self.source_line(loc.line))
        return value

    def si_args(self, children: Children) -> SiArguments:
        return SiArguments(nodes(children, SiArgument))

    def si_arg(self, children: Children) -> SiArgument:
        return SiArgument(self.name(token(children, "NAME")), node(children, SignedNumber).value, self.loc(children))

    def signed_number(self, children: Children) -> SignedNumber:
        tok = token(children, "INT", "FLOAT", "HEX")
        text = str(tok)
        if tok.type == "HEX":
            value: int | float = int(text, 16)
        elif tok.type == "INT":
            value = int(text)
        else:
            value = float(text)
        negative = maybe_token(children, "MINUS") is not None
        return SignedNumber(-value if negative else value, self.loc(children))

    def enum_decl(self, children: Children) -> s.EnumDecl:
        members = nodes(children, s.EnumMember)
        return s.EnumDecl(self.name(token(children, "NAME")), members, self.loc(children))

    def enum_member(self, children: Children) -> s.EnumMember:
        value = maybe_token(children, "INT", "HEX")
        number = None
        if value is not None:
            number = int(str(value), 16) if value.type == "HEX" else int(str(value))
        return s.EnumMember(self.name(token(children, "NAME")), number, self.loc(children))

    def enum_extend_decl(self, children: Children) -> NoReturn:
        raise self.unsupported("extending an enum", token(children, "EXTEND"))

    # ------------------------------------------------------------------ type declarations

    def type_decl(self, children: Children) -> s.TypeDecl:
        kind = token(children, "STRUCT", "ACTOR", "ACTION", "SCENARIO")
        inherits = maybe_node(children, Inherits)
        members = tuple(c for c in built(children) if not isinstance(c, (s.QualifiedName, Inherits)))
        return s.TypeDecl(str(kind), node(children, s.QualifiedName), inherits.parent if inherits else None,
                          members, self.loc(children))

    def inherits(self, children: Children) -> Inherits:
        condition = maybe_node(children, Marker)
        if condition is not None:
            raise self.unsupported("conditional inheritance", condition.location)
        return Inherits(node(children, s.QualifiedName))

    def inherits_condition(self, children: Children) -> Marker:
        return Marker(self.loc(children))

    def modifier_decl(self, children: Children) -> s.TypeDecl:
        name = node(children, s.QualifiedName)
        if len(name.parts) > 1:
            raise self.unsupported("actor modifiers (modifier actor.name)", name.location)
        of = maybe_node(children, Marker)
        if of is not None:
            raise self.unsupported("modifier ... of ...", of.location)
        members = tuple(c for c in built(children) if c is not name)
        return s.TypeDecl("modifier", name, None, members, self.loc(children))

    def modifier_of(self, children: Children) -> Marker:
        return Marker(self.loc(children))

    def extend_decl(self, children: Children) -> s.Extension:
        target = node(children, s.QualifiedName)
        members = tuple(c for c in built(children) if c is not target)
        return s.Extension(target, members, self.loc(children))

    # ------------------------------------------------------------------ members

    def _param_parts(self, children: Children) -> tuple[tuple[str, ...], s.TypeRef, s.Expression | None,
                                                         tuple[s.WithMember, ...]]:
        names = tuple(self.name(t) for t in tokens(children, "NAME"))
        default = maybe_node(children, Default)
        with_block = maybe_node(children, WithBlock)
        return (names, node(children, s.TypeRef), default.value if default else None,
                with_block.members if with_block else ())

    def param_decl(self, children: Children) -> s.ParameterDecl:
        names, type_ref, default, with_members = self._param_parts(children)
        return s.ParameterDecl(names, type_ref, default, with_members, self.loc(children))

    def global_decl(self, children: Children) -> s.ParameterDecl:
        names, type_ref, default, with_members = self._param_parts(children)
        return s.ParameterDecl(names, type_ref, default, with_members, self.loc(children), is_global=True)

    def var_decl(self, children: Children) -> s.VariableDecl:
        names, type_ref, default, _ = self._param_parts(children)
        return s.VariableDecl(names, type_ref, default, self.loc(children))

    def default(self, children: Children) -> Default:
        (value,) = built(children)
        return Default(value, self.loc(children))

    def type_ref(self, children: Children) -> s.TypeRef:
        is_list = maybe_token(children, "LIST") is not None
        return s.TypeRef(node(children, s.QualifiedName), is_list, self.loc(children))

    def event_decl(self, children: Children) -> s.EventDecl:
        condition = maybe_node(children, Marker)
        if condition is not None:
            raise self.unsupported("event ... is <condition>", condition.location)
        params = maybe_node(children, MethodParams)
        return s.EventDecl(self.name(token(children, "NAME")), params.params if params else (),
                           self.loc(children))

    def event_is(self, children: Children) -> Marker:
        return Marker(self.loc(children))

    def method_decl(self, children: Children) -> s.MethodDecl:
        params = maybe_node(children, MethodParams)
        impl = node(children, ExternalImpl)
        return s.MethodDecl(self.name(token(children, "NAME")), params.params if params else (),
                            maybe_node(children, s.TypeRef), impl.function, impl.arguments, self.loc(children))

    def method_params(self, children: Children) -> MethodParams:
        return MethodParams(nodes(children, s.MethodParameter))

    def method_param(self, children: Children) -> s.MethodParameter:
        default = maybe_node(children, Default)
        return s.MethodParameter(self.name(token(children, "NAME")), node(children, s.TypeRef),
                                 default.value if default else None, self.loc(children))

    def external_impl(self, children: Children) -> ExternalImpl:
        only = maybe_token(children, "ONLY")
        if only is not None:
            raise self.unsupported("'only' methods", only)
        return ExternalImpl(node(children, s.QualifiedName), arguments_of(children))

    def expression_impl(self, children: Children) -> NoReturn:
        raise self.unsupported("methods implemented by 'is expression'", token(children, "ONLY", "EXPRESSION"))

    def undefined_impl(self, children: Children) -> NoReturn:
        raise self.unsupported("methods declared 'is undefined'", token(children, "ONLY", "UNDEFINED"))

    def with_block(self, children: Children) -> WithBlock:
        members = built(children)
        return WithBlock(members, self.loc(members))

    def keep_stmt(self, children: Children) -> s.KeepConstraint:
        return node(children, s.KeepConstraint)

    def keep(self, children: Children) -> s.KeepConstraint:
        (constraint,) = built(children)
        is_default = maybe_token(children, "DEFAULT") is not None
        return s.KeepConstraint(constraint, is_default, self.loc(children))

    def modifier_stmt(self, children: Children) -> s.CoverageDecl | s.ModifierInvocation:
        (call,) = built(children)
        return call

    def modifier_call(self, children: Children) -> s.CoverageDecl | s.ModifierInvocation:
        name = node(children, s.QualifiedName)
        arguments = arguments_of(children)
        if len(name.parts) == 1 and name.parts[0] in COVERAGE_MEMBERS:
            return s.CoverageDecl(name.parts[0], arguments, self.loc(children))
        self.check_call_name(name)
        return s.ModifierInvocation(name, arguments, self.loc(children))

    def until_stmt(self, children: Children) -> s.Until:
        (condition,) = built(children)
        return s.Until(condition, self.loc(children))

    def on_directive(self, children: Children) -> NoReturn:
        raise self.unsupported("on @event", token(children, "ON"))

    def do_directive(self, children: Children) -> s.DoDirective:
        (member,) = built(children)
        return s.DoDirective(member, self.loc(children))
