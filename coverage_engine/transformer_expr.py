"""Transformer rules for behaviours (``do`` members) and expressions; mixed into the one SyntaxBuilder.

Kept apart from :mod:`coverage_engine.transformer` only for size. Unary minus directly on a number
literal is folded into the literal (``-2.0rad`` is one :class:`PhysicalLiteral` spanning the sign),
every other unary minus stays a :class:`UnaryOp`.
"""

from __future__ import annotations

from lark import Token, Transformer, v_args

from coverage_engine import syntax as s
from coverage_engine.errors import OscSyntaxError
from coverage_engine.strings import unescape_string


@v_args(meta=True)
class BehaviorExpressionRules(Transformer):
    """Rules for behaviours and expressions; relies on the helpers of ``SyntaxBuilder``."""

    # ------------------------------------------------------------------ behaviours

    def labelled(self, meta, children):
        label, behavior = children
        # dataclasses are frozen: rebuild with the label and a span that includes it
        fields = {f: getattr(behavior, f) for f in behavior.__dataclass_fields__}
        fields["label"] = self.name(label)
        fields["location"] = self.loc(meta)
        return type(behavior)(**fields)

    def composite(self, meta, children):
        kind, arguments, *rest = children
        with_members: tuple = ()
        if rest and isinstance(rest[-1], tuple):
            with_members = rest.pop()
        return s.Composite(str(kind), None, tuple(rest), arguments or (), with_members, self.loc(meta))

    def composite_args(self, meta, children):
        return children[0] or ()

    def invocation(self, meta, children):
        name, arguments, *rest = children
        self.check_call_name(name)
        with_members = rest[0] if rest else ()
        return s.Invocation(None, name, arguments or (), with_members, self.loc(meta))

    def wait(self, meta, children):
        return s.Wait(None, children[1], self.loc(meta))

    def wait_condition(self, meta, children):
        condition, *extra = children
        for c in extra:
            if c is not None:
                raise self.unsupported(c[0], c[1])
        return condition

    def event_as(self, meta, children):
        return ("event field declarations (as ...)", self.loc(meta))

    def event_if(self, meta, children):
        return ("event conditions (if ...)", self.loc(meta))

    def event_ref(self, meta, children):
        return s.EventRef((self.name(children[0]),), self.loc(meta))

    def emit(self, meta, children):
        _, name, *arguments = children
        return s.Emit(None, self.name(name), arguments[0] if arguments else (), self.loc(meta))

    def emit_args(self, meta, children):
        return children[0] or ()

    def call(self, meta, children):
        expr = children[1]
        if not isinstance(expr, s.Call):
            loc = expr.location
            raise OscSyntaxError("'call' needs a method call, e.g. call lib.method()", loc,
                                 self.source_line(loc.line))
        return s.CallDirective(None, expr, self.loc(meta))

    # ------------------------------------------------------------------ arguments

    def arguments(self, meta, children):
        seen_named = False
        for arg in children:
            if arg.name is not None:
                seen_named = True
            elif seen_named:
                loc = arg.location
                raise OscSyntaxError("positional argument after a named argument", loc,
                                     self.source_line(loc.line),
                                     "write positional arguments first, then the named ones")
        return tuple(children)

    def named_argument(self, meta, children):
        name, value = children
        return s.Argument(self.name(name), value, self.loc(meta))

    def positional_argument(self, meta, children):
        return s.Argument(None, children[0], self.loc(meta))

    # ------------------------------------------------------------------ expressions

    def ternary(self, meta, children):
        cond, if_true, if_false = children
        return s.Ternary(cond, if_true, if_false, self.loc(meta))

    def binary(self, meta, children):
        left, op, right = children
        return s.BinaryOp(str(op), left, right, self.loc(meta))

    def unary(self, meta, children):
        op, operand = children
        loc = self.loc(meta)
        if op == "+":
            if isinstance(operand, (s.Literal, s.PhysicalLiteral)) and operand.location.start_pos == op.end_pos:
                return type(operand)(**{**{f: getattr(operand, f) for f in operand.__dataclass_fields__},
                                        "location": loc})
            return operand
        if op == "-" and operand.location.start_pos == op.end_pos:
            if isinstance(operand, s.Literal) and operand.kind in ("int", "float"):
                return s.Literal(operand.kind, -operand.value, loc)
            if isinstance(operand, s.PhysicalLiteral):
                return s.PhysicalLiteral(-operand.number, operand.unit, loc)
        return s.UnaryOp(str(op), operand, loc)

    def member(self, meta, children):
        target, name = children
        if isinstance(target, s.EventRef):  # @actor.event: one event path, not a field access
            return s.EventRef(target.path + (self.name(name),), self.loc(meta))
        return s.MemberAccess(target, self.name(name), self.loc(meta))

    def call_expr(self, meta, children):
        callee, arguments = children
        if isinstance(callee, s.MemberAccess) and callee.member in ("as", "is"):
            raise self.unsupported(f"type {'casts' if callee.member == 'as' else 'tests'} (.{callee.member}())",
                                   callee.location)
        if isinstance(callee, s.Identifier) and callee.name in self.UNSUPPORTED_EXPR_CALLS:
            raise self.unsupported(self.UNSUPPORTED_EXPR_CALLS[callee.name], callee.location)
        return s.Call(callee, arguments or (), self.loc(meta))

    def element_access(self, meta, children):
        raise self.unsupported("element access (list[index])", self.loc(meta))

    def int_lit(self, meta, children):
        return s.Literal("int", int(str(children[0])), self.loc(meta))

    def hex_lit(self, meta, children):
        return s.Literal("int", int(str(children[0]), 16), self.loc(meta))

    def float_lit(self, meta, children):
        return s.Literal("float", float(str(children[0])), self.loc(meta))

    def string_lit(self, meta, children):
        return s.Literal("string", unescape_string(str(children[0])), self.loc(meta))

    def bool_lit(self, meta, children):
        return s.Literal("bool", str(children[0]) == "true", self.loc(meta))

    def physical(self, meta, children):
        number, unit = children
        value: int | float = float(str(number)) if number.type == "FLOAT" else int(str(number))
        return s.PhysicalLiteral(value, self.name(unit), self.loc(meta))

    def identifier(self, meta, children):
        return s.Identifier(self.name(children[0]), self.loc(meta))

    def list_expr(self, meta, children):
        items = tuple(c for c in children if c is not None and not isinstance(c, Token))
        return s.ListExpr(items, self.loc(meta))

    def range_expr(self, meta, children):
        low, high = (c for c in children if not isinstance(c, Token))
        return s.RangeExpr(low, high, self.loc(meta))

    def enum_ref(self, meta, children):
        enum, member = children
        return s.EnumValueRef(self.name(enum), self.name(member), self.loc(meta))

    def enum_ref_bare(self, meta, children):
        return s.EnumValueRef(None, self.name(children[0]), self.loc(meta))
