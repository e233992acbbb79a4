"""Transformer rules for behaviours (``do`` members) and expressions, and the location helpers.

Kept apart from :mod:`coverage_engine.parse.transformer` only for size. Expressions arrive as a flat run of
operands and operator tokens; :meth:`BehaviorExpressionRules.expr` applies precedence by climbing.
Unary minus written directly before a number literal is folded into it (``-2.0rad`` is one
:class:`PhysicalLiteral` spanning the sign); any other unary minus stays a :class:`UnaryOp`.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any, NoReturn, Protocol, cast

from coverage_engine.errors import OscSyntaxError, UnsupportedFeatureError
from coverage_engine.location import Location
from coverage_engine.parse import syntax as s
from coverage_engine.parse.lexer import Token
from coverage_engine.parse.parts import (
    ArgumentList,
    Refusal,
    WithBlock,
    arguments_of,
    built,
    maybe_node,
    nodes,
    token,
)
from coverage_engine.parse.strings import unescape_string
from coverage_engine.records import replace

# Names the reference reserves for features we do not implement; written like a call they would
# otherwise parse as an ordinary modifier/behaviour invocation or function call.
UNSUPPORTED_STATEMENTS = {"cover": "cover() in a behaviour (it is a member of a scenario or of a parameter's "
                                   "'with:' block)",
                          "record": "record() in a behaviour (it is a member of a scenario or of a parameter's "
                                    "'with:' block)",
                          "remove_default": "remove_default()"}
UNSUPPORTED_EXPR_CALLS = {
    "sample": "sample()",
    "rise": "rise()", "fall": "fall()", "every": "every()",
}
BINARY_PRECEDENCE = {
    "=>": 1, "or": 2, "and": 3,
    "==": 5, "!=": 5, "<": 5, "<=": 5, ">": 5, ">=": 5, "in": 5,
    "+": 6, "-": 6, "*": 7, "/": 7, "%": 7,
}
PREFIX_PRECEDENCE = {"not": 4, "-": 8, "+": 8}
_LINE_BREAK = re.compile(r"\r\n|\r|\n")

#: What a rule's callback receives: the rule's tokens and the values its sub-rules built (syntax nodes and
#: the records of :mod:`~coverage_engine.parse.parts`), in written order. The table-driven parser does not
#: type them; :mod:`~coverage_engine.parse.parts` finds each by name or class.
Children = list[Any]


class Located(Protocol):
    """A syntax node or a part record: anything with a location."""

    @property
    def location(self) -> Location: ...


#: What a location can be taken from: a token, a node, a location, or a run of them (first and last count).
Spanned = Token | Location | Located | tuple[Any, ...] | list[Any]


def _start(x: Spanned) -> tuple[int, int, int]:
    """(line, column, offset) where ``x`` (token, node, or tuple of nodes) begins."""
    if isinstance(x, Token):
        return x.line, x.column, x.start_pos
    if isinstance(x, (tuple, list)):
        return _start(x[0])
    loc = x.location if not isinstance(x, Location) else x
    return loc.line, loc.column, loc.start_pos


def _end(x: Spanned) -> tuple[int, int, int]:
    """(line, column, offset) just after ``x``."""
    if isinstance(x, Token):
        return x.end_line, x.end_column, x.end_pos
    if isinstance(x, (tuple, list)):
        return _end(x[-1])
    loc = x.location if not isinstance(x, Location) else x
    return loc.end_line, loc.end_column, loc.end_pos


class BehaviorExpressionRules:
    """Rules for behaviours and expressions plus the helpers every rule uses."""

    def __init__(self) -> None:
        self.file = "<string>"
        self.text = ""
        self._lines: list[str] | None = None

    def reset(self, file: str, text: str) -> None:
        """Prepare for one parse of ``text`` named ``file``."""
        self.file, self.text, self._lines = file, text, None

    # ------------------------------------------------------------------ helpers

    def loc(self, children: Sequence[Any]) -> Location:
        items = [c for c in children if c is not None and not (isinstance(c, tuple) and not c)]
        if not items:
            return Location(self.file, 1, 1, 1, 1, 0, 0)
        line, column, start = _start(items[0])
        end_line, end_column, end = _end(items[-1])
        return Location(self.file, line, column, end_line, end_column, start, end)

    def tloc(self, tok: Token) -> Location:
        return Location(self.file, tok.line, tok.column, tok.end_line, tok.end_column,
                          tok.start_pos, tok.end_pos)

    def span(self, first: Spanned, last: Spanned) -> Location:
        line, column, start = _start(first)
        end_line, end_column, end = _end(last)
        return Location(self.file, line, column, end_line, end_column, start, end)

    def source_line(self, line: int) -> str | None:
        if self._lines is None:
            self._lines = _LINE_BREAK.split(self.text)
        return self._lines[line - 1] if 0 < line <= len(self._lines) else None

    def unsupported(self, what: str, where: Token | Location) -> UnsupportedFeatureError:
        loc = self.tloc(where) if isinstance(where, Token) else where
        return UnsupportedFeatureError(f"not supported: {what}", loc, self.source_line(loc.line))

    @staticmethod
    def name(tok: Token) -> str:
        value = str(tok)
        if value[:1] == "|" and value[-1:] == "|" and len(value) > 1:
            return value[1:-1]
        return value

    def check_call_name(self, name: s.QualifiedName) -> None:
        if len(name.parts) == 1 and name.parts[0] in UNSUPPORTED_STATEMENTS:
            raise self.unsupported(UNSUPPORTED_STATEMENTS[name.parts[0]], name.location)

    # ------------------------------------------------------------------ behaviours

    def labelled(self, children: Children) -> s.Behavior:
        (behavior,) = built(children)
        return replace(behavior, label=self.name(token(children, "NAME")), location=self.loc(children))

    def composite(self, children: Children) -> s.Composite:
        kind = token(children, "SERIAL", "PARALLEL", "ONE_OF")
        with_block = maybe_node(children, WithBlock)
        members = tuple(c for c in built(children) if not isinstance(c, (ArgumentList, WithBlock)))
        return s.Composite(str(kind), None, members, arguments_of(children),
                           with_block.members if with_block else (), self.loc(children))

    def composite_args(self, children: Children) -> ArgumentList:
        return ArgumentList(arguments_of(children))

    def invocation(self, children: Children) -> s.Invocation:
        name, _open, *inside, _close, end = children
        self.check_call_name(name)
        with_members = end.members if type(end) is WithBlock else ()
        return s.Invocation(None, name, arguments_of(inside), with_members, self.loc(children))

    def wait(self, children: Children) -> s.Wait:
        (condition,) = built(children)
        return s.Wait(None, condition, self.loc(children))

    def wait_condition(self, children: Children) -> s.Expression:
        if len(children) == 1:
            (condition,) = children
            return condition
        refused = maybe_node(children, Refusal)
        if refused is not None:
            raise self.unsupported(refused.what, refused.location)
        (condition,) = children
        return condition

    def event_as(self, children: Children) -> Refusal:
        return Refusal("event field declarations (as ...)", self.loc(children))

    def event_if(self, children: Children) -> Refusal:
        return Refusal("event conditions (if ...)", self.loc(children))

    def emit(self, children: Children) -> s.Emit:
        return s.Emit(None, self.name(token(children, "NAME")), arguments_of(children), self.loc(children))

    def emit_args(self, children: Children) -> ArgumentList:
        return ArgumentList(arguments_of(children))

    def call(self, children: Children) -> s.CallDirective:
        (expr,) = built(children)
        if not isinstance(expr, s.Call):
            loc = expr.location
            raise OscSyntaxError("'call' needs a method call, e.g. call lib.method()", loc,
                                 self.source_line(loc.line))
        return s.CallDirective(None, expr, self.loc(children))

    # ------------------------------------------------------------------ arguments

    def arguments(self, children: Children) -> ArgumentList:
        args = nodes(children, s.Argument)
        seen_named = False
        for arg in args:
            if arg.name is not None:
                seen_named = True
            elif seen_named:
                raise OscSyntaxError("positional argument after a named argument", arg.location,
                                     self.source_line(arg.location.line),
                                     "write positional arguments first, then the named ones")
        return ArgumentList(args)

    def named_argument(self, children: Children) -> s.Argument:
        name, _colon, value = children
        return s.Argument(self.name(name), value, self.loc(children))

    def positional_argument(self, children: Children) -> s.Argument:
        (value,) = children
        return s.Argument(None, value, self.loc(children))

    # ------------------------------------------------------------------ expressions

    def expr(self, children: Children) -> s.Expression:
        """A run ``operand (operator operand)*``, with prefix operators, then an optional ``? then : else``."""
        if len(children) == 1:
            (only,) = children
            return only
        if len(children) >= 5:
            *run, question, then, _colon, otherwise = children
            if isinstance(question, Token) and question.value == "?":
                condition = self._climb(run)
                return s.Ternary(condition, then, otherwise, self.span(condition, otherwise))
        return self._climb(children)

    def _climb(self, items: Children) -> s.Expression:
        if len(items) == 1:
            return items[0]
        tree, _ = self._climb_from(items, 0, 0)
        return tree

    def _climb_from(self, items: Children, pos: int, min_prec: int) -> tuple[s.Expression, int]:
        first = items[pos]
        if isinstance(first, Token):  # prefix operator
            operand, pos = self._climb_from(items, pos + 1, PREFIX_PRECEDENCE[str(first)])
            left = self._unary(first, operand)
        else:
            left, pos = first, pos + 1
        while pos < len(items):
            op = items[pos]
            prec = BINARY_PRECEDENCE[str(op)]
            if prec < min_prec:
                break
            right, pos = self._climb_from(items, pos + 1, prec + 1)
            left = s.BinaryOp(str(op), left, right, self.span(left, right))
        return left, pos

    def _unary(self, op: Token, operand: s.Expression) -> s.Expression:
        loc = self.span(op, operand)
        adjacent = operand.location.start_pos == op.end_pos
        if op.value == "+":
            if adjacent and isinstance(operand, (s.Literal, s.PhysicalLiteral)):
                return replace(operand, location=loc)
            return operand
        if op.value == "-" and adjacent:
            if isinstance(operand, s.Literal) and operand.kind in ("int", "float"):
                return s.Literal(operand.kind, -cast("int | float", operand.value), loc)
            if isinstance(operand, s.PhysicalLiteral):
                return s.PhysicalLiteral(-operand.number, operand.unit, loc)
        return s.UnaryOp(str(op), operand, loc)

    def paren(self, children: Children) -> s.Expression:
        _open, inner, _close = children
        return inner

    def member(self, children: Children) -> s.EventRef | s.MemberAccess:
        target, _dot, name = children
        if isinstance(target, s.EventRef):  # @actor.event: one event path, not a field access
            return s.EventRef(target.path + (self.name(name),), self.loc(children))
        return s.MemberAccess(target, self.name(name), self.loc(children))

    def call_expr(self, children: Children) -> s.Call:
        callee, _open, *inside, _close = children
        if isinstance(callee, s.MemberAccess) and callee.member in ("as", "is"):
            what = "type casts" if callee.member == "as" else "type tests"
            raise self.unsupported(f"{what} (.{callee.member}())", callee.location)
        if isinstance(callee, s.Identifier) and callee.name in UNSUPPORTED_EXPR_CALLS:
            raise self.unsupported(UNSUPPORTED_EXPR_CALLS[callee.name], callee.location)
        return s.Call(callee, arguments_of(inside), self.loc(children))

    def element_access(self, children: Children) -> NoReturn:
        raise self.unsupported("element access (list[index])", self.loc(children))

    def int_lit(self, children: Children) -> s.Literal:
        (tok,) = children
        return s.Literal("int", int(str(tok)), self.tloc(tok))

    def hex_lit(self, children: Children) -> s.Literal:
        (tok,) = children
        return s.Literal("int", int(str(tok), 16), self.tloc(tok))

    def float_lit(self, children: Children) -> s.Literal:
        (tok,) = children
        return s.Literal("float", float(str(tok)), self.tloc(tok))

    def string_lit(self, children: Children) -> s.Literal:
        (tok,) = children
        return s.Literal("string", unescape_string(str(tok)), self.tloc(tok))

    def bool_lit(self, children: Children) -> s.Literal:
        (tok,) = children
        return s.Literal("bool", tok.type == "TRUE", self.tloc(tok))

    def physical(self, children: Children) -> s.PhysicalLiteral:
        number, unit = children
        value: int | float = float(str(number)) if number.type == "FLOAT" else int(str(number))
        return s.PhysicalLiteral(value, self.name(unit), self.loc(children))

    def identifier(self, children: Children) -> s.Identifier:
        (tok,) = children
        return s.Identifier(self.name(tok), self.tloc(tok))

    def list_expr(self, children: Children) -> s.ListExpr:
        return s.ListExpr(built(children), self.loc(children))

    def range_expr(self, children: Children) -> s.RangeExpr:
        _open, low, _dots, high, _close = children
        return s.RangeExpr(low, high, self.loc(children))

    def range_expr_unit(self, children: Children) -> s.RangeExpr:
        """Foretify's ``[10..50]kph``: the unit after the bracket applies to both (plain number) ends."""
        _open, low, _dots, high, _close, unit = children
        name = self.name(unit)
        return s.RangeExpr(_with_unit(low, name), _with_unit(high, name), self.loc(children))

    def enum_ref(self, children: Children) -> s.EnumValueRef:
        type_name, _bang, member = children
        return s.EnumValueRef(self.name(type_name), self.name(member), self.loc(children))

    def enum_ref_bare(self, children: Children) -> s.EnumValueRef:
        _bang, member = children
        return s.EnumValueRef(None, self.name(member), self.loc(children))

    def event_ref(self, children: Children) -> s.EventRef:
        _at, name = children
        return s.EventRef((self.name(name),), self.loc(children))


def _with_unit(end: s.Expression, unit: str) -> s.Expression:
    """A range end ``10`` or ``-2.5`` of ``[10..50]kph`` as the physical literal ``10kph``; anything else
    stays as written (the range's user says that a range end must be a plain number)."""
    sign = 1
    number = end
    if isinstance(number, s.UnaryOp) and number.op in ("-", "+"):
        sign = -1 if number.op == "-" else 1
        number = number.operand
    if isinstance(number, s.Literal) and number.kind in ("int", "float") and not isinstance(number.value, bool):
        return s.PhysicalLiteral(sign * number.value, unit, end.location)  # type: ignore[operator]
    return end
