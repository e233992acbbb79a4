"""The one lark Transformer that turns the parse tree of ``grammar.lark`` into :mod:`coverage_engine.syntax` nodes.

No semantics here: names are not looked up, units not converted, nothing evaluated. Constructs the
grammar accepts only so they can be refused by name (``cover``, ``on @event``, ``sample`` …) are
rejected here with :class:`UnsupportedFeatureError` at their position.
"""

from __future__ import annotations

from lark import Token, v_args

from coverage_engine import syntax as s
from coverage_engine.errors import OscSyntaxError, UnsupportedFeatureError
from coverage_engine.strings import unescape_string
from coverage_engine.transformer_expr import BehaviorExpressionRules

# Names the reference reserves for features we do not implement; written like a call they would
# otherwise parse as an ordinary modifier or method invocation.
UNSUPPORTED_CALLS = {
    "cover": "cover()",
    "record": "record()",
    "remove_default": "remove_default()",
}
UNSUPPORTED_EXPR_CALLS = {
    "sample": "sample()",
    "range": "range() (write [low..high] instead)",
    "rise": "rise()",
    "fall": "fall()",
    "every": "every()",
}


@v_args(meta=True)
class SyntaxBuilder(BehaviorExpressionRules):
    """Builds syntax nodes; ``file`` names the source in every :class:`~coverage_engine.syntax.Location`."""

    UNSUPPORTED_EXPR_CALLS = UNSUPPORTED_EXPR_CALLS

    def __init__(self, file: str, text: str) -> None:
        super().__init__(visit_tokens=False)
        self.file = file
        self.text = text

    # ------------------------------------------------------------------ locations and helpers

    def loc(self, meta) -> s.Location:
        if getattr(meta, "empty", True):
            return s.Location(self.file, 1, 1, 1, 1, 0, 0)
        return s.Location(self.file, meta.line, meta.column, meta.end_line, meta.end_column,
                          meta.start_pos, meta.end_pos)

    def tloc(self, tok: Token) -> s.Location:
        return s.Location(self.file, tok.line, tok.column, tok.end_line, tok.end_column,
                          tok.start_pos, tok.end_pos)

    def span(self, first: s.Location, last: s.Location) -> s.Location:
        return s.Location(self.file, first.line, first.column, last.end_line, last.end_column,
                          first.start_pos, last.end_pos)

    def unsupported(self, what: str, where: s.Location | Token) -> UnsupportedFeatureError:
        loc = self.tloc(where) if isinstance(where, Token) else where
        return UnsupportedFeatureError(f"not supported: {what}", loc, self.source_line(loc.line))

    def source_line(self, line: int) -> str | None:
        lines = self.text.splitlines()
        return lines[line - 1] if 0 < line <= len(lines) else None

    @staticmethod
    def name(tok: Token) -> str:
        value = str(tok)
        if value.startswith("|") and value.endswith("|") and len(value) > 1:
            return value[1:-1]
        return value

    def check_call_name(self, name: s.QualifiedName) -> None:
        if len(name.parts) == 1 and name.parts[0] in UNSUPPORTED_CALLS:
            raise self.unsupported(UNSUPPORTED_CALLS[name.parts[0]], name.location)

    # ------------------------------------------------------------------ file level

    def start(self, meta, children):
        imports = tuple(c for c in children if isinstance(c, s.Import))
        decls = tuple(c for c in children if not isinstance(c, s.Import))
        return s.CompilationUnit(self.file, imports, decls, self.text)

    def import_stmt(self, meta, children):
        (ref,) = children
        if isinstance(ref, Token):
            return s.Import(unescape_string(str(ref)), True, self.loc(meta))
        return s.Import(ref.dotted, False, self.loc(meta))

    def qualified_name(self, meta, children):
        return s.QualifiedName(tuple(self.name(t) for t in children), self.loc(meta))

    def namespace_decl(self, meta, children):
        raise self.unsupported("namespaces", children[0])

    def physical_type_decl(self, meta, children):
        name, args = children
        exps = []
        for arg_name, value, loc in args:
            if arg_name in ("factor", "offset"):
                raise OscSyntaxError(f"'{arg_name}' belongs in a unit declaration, not a type", loc,
                                     self.source_line(loc.line))
            exps.append((arg_name, self.exponent(value, loc)))
        return s.PhysicalTypeDecl(self.name(name), tuple(exps), self.loc(meta))

    def unit_decl(self, meta, children):
        name, type_name, args = children
        exps, factor, offset = [], None, None
        for arg_name, value, loc in args:
            if arg_name == "factor":
                factor = float(value)
            elif arg_name == "offset":
                offset = float(value)
            else:
                exps.append((arg_name, self.exponent(value, loc)))
        return s.UnitDecl(self.name(name), self.name(type_name), tuple(exps), factor, offset, self.loc(meta))

    def exponent(self, value: int | float, loc: s.Location) -> int:
        if not isinstance(value, int):
            raise OscSyntaxError("an SI exponent must be an integer", loc, self.source_line(loc.line))
        return value

    def si_args(self, meta, children):
        return children

    def si_arg(self, meta, children):
        name, value = children
        return (self.name(name), value, self.loc(meta))

    def signed_number(self, meta, children):
        *sign, tok = children
        text = str(tok)
        if tok.type == "HEX":
            value: int | float = int(text, 16)
        elif tok.type == "INT":
            value = int(text)
        else:
            value = float(text)
        return -value if sign else value

    def enum_decl(self, meta, children):
        name, *members = children
        return s.EnumDecl(self.name(name), tuple(members), self.loc(meta))

    def enum_member(self, meta, children):
        name, value = children[0], (children[1] if len(children) > 1 else None)
        number = None
        if value is not None:
            number = int(str(value), 16) if value.type == "HEX" else int(str(value))
        return s.EnumMember(self.name(name), number, self.loc(meta))

    def enum_extend_decl(self, meta, children):
        raise self.unsupported("extending an enum", children[0])

    # ------------------------------------------------------------------ type declarations

    def type_decl(self, meta, children):
        kind, name, *rest = children
        parent = None
        if rest and isinstance(rest[0], s.QualifiedName):
            parent = rest.pop(0)
        return s.TypeDecl(str(kind), name, parent, tuple(rest), self.loc(meta))

    def inherits(self, meta, children):
        if len(children) > 1:
            raise self.unsupported("conditional inheritance", children[1])
        return children[0]

    def inherits_condition(self, meta, children):
        return self.loc(meta)

    def modifier_decl(self, meta, children):
        name, *rest = children
        if len(name.parts) > 1:
            raise self.unsupported("actor modifiers (modifier actor.name)", name.location)
        if rest and isinstance(rest[0], s.Location):
            raise self.unsupported("modifier ... of ...", rest[0])
        return s.TypeDecl("modifier", name, None, tuple(rest), self.loc(meta))

    def modifier_of(self, meta, children):
        return self.loc(meta)

    def extend_decl(self, meta, children):
        _, name, *members = children
        return s.Extension(name, tuple(members), self.loc(meta))

    # ------------------------------------------------------------------ members

    def _param_parts(self, children):
        names, type_ref, default, with_members = [], None, None, ()
        for c in children:
            if isinstance(c, Token):
                names.append(self.name(c))
            elif isinstance(c, s.TypeRef):
                type_ref = c
            elif isinstance(c, tuple):
                with_members = c
            else:
                default = c
        return tuple(names), type_ref, default, with_members

    def param_decl(self, meta, children):
        names, type_ref, default, with_members = self._param_parts(children)
        return s.ParameterDecl(names, type_ref, default, with_members, self.loc(meta))

    def global_decl(self, meta, children):
        names, type_ref, default, with_members = self._param_parts(children)
        return s.ParameterDecl(names, type_ref, default, with_members, self.loc(meta), is_global=True)

    def var_decl(self, meta, children):
        names, type_ref, default, _ = self._param_parts(children)
        return s.VariableDecl(names, type_ref, default, self.loc(meta))

    def default(self, meta, children):
        return children[0]

    def type_ref(self, meta, children):
        if len(children) == 2:
            return s.TypeRef(children[1], True, self.loc(meta))
        return s.TypeRef(children[0], False, self.loc(meta))

    def event_decl(self, meta, children):
        name, *rest = children
        params: tuple = ()
        for c in rest:
            if isinstance(c, tuple):
                params = c
            elif isinstance(c, s.Location):
                raise self.unsupported("event ... is <condition>", c)
        return s.EventDecl(self.name(name), params, self.loc(meta))

    def event_is(self, meta, children):
        return self.loc(meta)

    def method_decl(self, meta, children):
        name, params, *rest = children
        return_type = rest[0] if len(rest) == 2 else None
        external, arguments = rest[-1]
        return s.MethodDecl(self.name(name), params or (), return_type, external, arguments, self.loc(meta))

    def method_params(self, meta, children):
        return tuple(children)

    def method_param(self, meta, children):
        name, type_ref, *default = children
        return s.MethodParameter(self.name(name), type_ref, default[0] if default else None, self.loc(meta))

    def external_impl(self, meta, children):
        if len(children) == 3:
            raise self.unsupported("'only' methods", children[0])
        name, arguments = children
        return name, arguments or ()

    def expression_impl(self, meta, children):
        raise self.unsupported("methods implemented by 'is expression'", self.loc(meta))

    def undefined_impl(self, meta, children):
        raise self.unsupported("methods declared 'is undefined'", self.loc(meta))

    def with_block(self, meta, children):
        return tuple(children)

    def keep_stmt(self, meta, children):
        return children[0]

    def keep(self, meta, children):
        qualifier = children[1] if len(children) == 3 else None
        return s.KeepConstraint(children[-1], qualifier is not None and str(qualifier) == "default",
                                self.loc(meta))

    def modifier_stmt(self, meta, children):
        return children[0]

    def modifier_call(self, meta, children):
        name, arguments = children
        self.check_call_name(name)
        return s.ModifierInvocation(name, arguments or (), self.loc(meta))

    def until_stmt(self, meta, children):
        raise self.unsupported("until", children[0])

    def on_directive(self, meta, children):
        raise self.unsupported("on @event", children[0])

    def do_directive(self, meta, children):
        return s.DoDirective(children[1], self.loc(meta))
