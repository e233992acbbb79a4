"""The one lark Transformer that turns ``grammar.lark`` matches into :mod:`coverage_engine.parse.syntax` nodes.

It runs inside the LALR parser (no intermediate parse tree) with every token kept, so each rule
sees its first and last token and computes its own :class:`~coverage_engine.parse.Location` --
exact to the character, which the variation generator needs to cut and replace source. No
semantics here: nothing is looked up, converted or evaluated. Constructs the grammar accepts only
so they can be refused by name (``cover``, ``on @event``, ``sample`` …) raise
:class:`UnsupportedFeatureError` at their position.
"""

from __future__ import annotations

from typing import Any, NoReturn

from coverage_engine.errors import OscSyntaxError
from coverage_engine.location import Location
from coverage_engine.parse import syntax as s
from coverage_engine.parse.lexer import Token
from coverage_engine.parse.transformer_expr import BehaviorExpressionRules, Children

#: Member statements that declare coverage items rather than apply a modifier.
COVERAGE_MEMBERS = ("cover", "record")


class SyntaxBuilder(BehaviorExpressionRules):
    """Callbacks for the declaration rules; expressions and behaviours come from the mixin."""

    # ------------------------------------------------------------------ file level

    def start(self, children: Children) -> s.CompilationUnit:
        imports = tuple(c for c in children if isinstance(c, s.Import))
        decls = tuple(c for c in children if not isinstance(c, (s.Import, Token)))
        return s.CompilationUnit(self.file, imports, decls, self.text)

    def import_stmt(self, children: Children) -> s.Import:
        ref = children[1]
        if isinstance(ref, Token):
            from coverage_engine.parse.strings import unescape_string

            return s.Import(unescape_string(str(ref)), True, self.loc(children))
        return s.Import(ref.dotted, False, self.loc(children))

    def qualified_name(self, children: Children) -> s.QualifiedName:
        if len(children) == 1:
            return s.QualifiedName((self.name(children[0]),), self.tloc(children[0]))
        return s.QualifiedName(tuple(self.name(t) for t in children if t.type == "NAME"), self.loc(children))

    def namespace_decl(self, children: Children) -> NoReturn:
        raise self.unsupported("namespaces", children[0])

    def physical_type_decl(self, children: Children) -> s.PhysicalTypeDecl:
        name, args = children[1], children[5]
        exps = []
        for arg_name, value, loc in args:
            if arg_name in ("factor", "offset"):
                raise OscSyntaxError(f"'{arg_name}' belongs in a unit declaration, not a type", loc,
                                     self.source_line(loc.line))
            exps.append((arg_name, self.exponent(value, loc)))
        return s.PhysicalTypeDecl(self.name(name), tuple(exps), self.loc(children))

    def unit_decl(self, children: Children) -> s.UnitDecl:
        name, type_name, args = children[1], children[3], children[7]
        exps, factor, offset = [], None, None
        for arg_name, value, loc in args:
            if arg_name == "factor":
                factor = float(value)
            elif arg_name == "offset":
                offset = float(value)
            else:
                exps.append((arg_name, self.exponent(value, loc)))
        return s.UnitDecl(self.name(name), self.name(type_name), tuple(exps), factor, offset,
                          self.loc(children))

    def exponent(self, value: int | float, loc: Location) -> int:
        if not isinstance(value, int):
            raise OscSyntaxError("an SI exponent must be an integer", loc, self.source_line(loc.line))
        return value

    def si_args(self, children: Children) -> list[tuple[str, int | float, Location]]:
        return [c for c in children if not isinstance(c, Token)]

    def si_arg(self, children: Children) -> tuple[str, int | float, Location]:
        return (self.name(children[0]), children[2][0], self.loc(children))

    def signed_number(self, children: Children) -> tuple[int | float, Location]:
        tok = children[-1]
        text = str(tok)
        if tok.type == "HEX":
            value: int | float = int(text, 16)
        elif tok.type == "INT":
            value = int(text)
        else:
            value = float(text)
        return (-value if len(children) > 1 else value), self.loc(children)

    def enum_decl(self, children: Children) -> s.EnumDecl:
        members = tuple(c for c in children if isinstance(c, s.EnumMember))
        return s.EnumDecl(self.name(children[1]), members, self.loc(children))

    def enum_member(self, children: Children) -> s.EnumMember:
        number = None
        if len(children) == 3:
            value = children[2]
            number = int(str(value), 16) if value.type == "HEX" else int(str(value))
        return s.EnumMember(self.name(children[0]), number, self.loc(children))

    def enum_extend_decl(self, children: Children) -> NoReturn:
        raise self.unsupported("extending an enum", children[0])

    # ------------------------------------------------------------------ type declarations

    def type_decl(self, children: Children) -> s.TypeDecl:
        kind, name = children[0], children[1]
        parent = children[2] if isinstance(children[2], s.QualifiedName) else None
        members = tuple(c for c in children[2:] if not isinstance(c, (Token, s.QualifiedName)))
        return s.TypeDecl(str(kind), name, parent, members, self.loc(children))

    def inherits(self, children: Children) -> s.QualifiedName:
        if len(children) > 2:
            raise self.unsupported("conditional inheritance", children[2])
        return children[1]

    def inherits_condition(self, children: Children) -> Location:
        return self.loc(children)

    def modifier_decl(self, children: Children) -> s.TypeDecl:
        name = children[1]
        if len(name.parts) > 1:
            raise self.unsupported("actor modifiers (modifier actor.name)", name.location)
        if isinstance(children[2], Location):
            raise self.unsupported("modifier ... of ...", children[2])
        members = tuple(c for c in children[2:] if not isinstance(c, Token))
        return s.TypeDecl("modifier", name, None, members, self.loc(children))

    def modifier_of(self, children: Children) -> Location:
        return self.loc(children)

    def extend_decl(self, children: Children) -> s.Extension:
        members = tuple(c for c in children[2:] if not isinstance(c, Token))
        return s.Extension(children[1], members, self.loc(children))

    # ------------------------------------------------------------------ members

    def _param_parts(self, children: Children) -> tuple[tuple[str, ...], s.TypeRef, s.Expression | None,
                                                         tuple[s.WithMember, ...]]:
        names, type_ref, default, with_members = [], None, None, ()
        for c in children:
            if isinstance(c, Token):
                if c.type == "NAME":
                    names.append(self.name(c))
            elif isinstance(c, s.TypeRef):
                type_ref = c
            elif isinstance(c, tuple):
                with_members = c
            else:
                default = c
        assert type_ref is not None, "the grammar requires ': type'"
        return tuple(names), type_ref, default, with_members

    def param_decl(self, children: Children) -> s.ParameterDecl:
        names, type_ref, default, with_members = self._param_parts(children)
        return s.ParameterDecl(names, type_ref, default, with_members, self.loc(children))

    def global_decl(self, children: Children) -> s.ParameterDecl:
        names, type_ref, default, with_members = self._param_parts(children)
        return s.ParameterDecl(names, type_ref, default, with_members, self.loc(children), is_global=True)

    def var_decl(self, children: Children) -> s.VariableDecl:
        names, type_ref, default, _ = self._param_parts(children)
        return s.VariableDecl(names, type_ref, default, self.loc(children))

    def default(self, children: Children) -> s.Expression:
        return children[1]

    def type_ref(self, children: Children) -> s.TypeRef:
        return s.TypeRef(children[-1], len(children) == 3, self.loc(children))

    def event_decl(self, children: Children) -> s.EventDecl:
        params: tuple = ()
        for c in children[2:]:
            if isinstance(c, tuple):
                params = c
            elif isinstance(c, Location):
                raise self.unsupported("event ... is <condition>", c)
        return s.EventDecl(self.name(children[1]), params, self.loc(children))

    def event_is(self, children: Children) -> Location:
        return self.loc(children)

    def method_decl(self, children: Children) -> s.MethodDecl:
        params: tuple = ()
        return_type = None
        impl = None
        for c in children[2:]:
            if isinstance(c, tuple) and c and isinstance(c[0], s.MethodParameter):
                params = c
            elif isinstance(c, s.TypeRef):
                return_type = c
            elif isinstance(c, list):
                impl = c
        assert impl is not None, "the grammar requires 'is external ...' (the other forms raise)"
        external, arguments = impl
        return s.MethodDecl(self.name(children[1]), params, return_type, external, arguments,
                            self.loc(children))

    def method_params(self, children: Children) -> tuple[s.MethodParameter, ...]:
        return tuple(c for c in children if isinstance(c, s.MethodParameter))

    def method_param(self, children: Children) -> s.MethodParameter:
        default = children[3] if len(children) > 3 else None
        return s.MethodParameter(self.name(children[0]), children[2], default, self.loc(children))

    def external_impl(self, children: Children) -> list[Any]:
        if children[0].type == "ONLY":
            raise self.unsupported("'only' methods", children[0])
        name = children[1]
        arguments = next((c for c in children if isinstance(c, tuple)), ())
        return [name, arguments]

    def expression_impl(self, children: Children) -> NoReturn:
        raise self.unsupported("methods implemented by 'is expression'", children[0])

    def undefined_impl(self, children: Children) -> NoReturn:
        raise self.unsupported("methods declared 'is undefined'", children[0])

    def with_block(self, children: Children) -> tuple[s.WithMember, ...]:
        return tuple(c for c in children if not isinstance(c, Token))

    def keep_stmt(self, children: Children) -> s.KeepConstraint:
        return children[0]

    def keep(self, children: Children) -> s.KeepConstraint:
        qualifier = children[2] if isinstance(children[2], Token) else None
        return s.KeepConstraint(children[-2], qualifier is not None and qualifier.type == "DEFAULT",
                                self.loc(children))

    def modifier_stmt(self, children: Children) -> s.CoverageDecl | s.ModifierInvocation:
        return children[0]

    def modifier_call(self, children: Children) -> s.CoverageDecl | s.ModifierInvocation:
        name = children[0]
        arguments = children[2] if isinstance(children[2], tuple) else ()
        if len(name.parts) == 1 and name.parts[0] in COVERAGE_MEMBERS:
            return s.CoverageDecl(name.parts[0], arguments, self.loc(children))
        self.check_call_name(name)
        return s.ModifierInvocation(name, arguments, self.loc(children))

    def until_stmt(self, children: Children) -> s.Until:
        return s.Until(children[1], self.loc(children))

    def on_directive(self, children: Children) -> NoReturn:
        raise self.unsupported("on @event", children[0])

    def do_directive(self, children: Children) -> s.DoDirective:
        return s.DoDirective(children[1], self.loc(children))
