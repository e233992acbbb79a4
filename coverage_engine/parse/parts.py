"""Reading a grammar rule's parts by name: the syntax builder never counts its children.

The LALR driver hands each rule of ``grammar.lark`` every token it matched (keywords and punctuation
too, so the rule knows where it starts and ends) and the values its sub-rules built, in order. Where a
rule has optional parts the positions shift, so a part is found by what it is: a token by its terminal
name (``token(children, "NAME")``), a built value by its class (``node(children, s.TypeRef)``). The
sub-rules that build no syntax node of their own (``with:`` blocks, argument lists, method parameter
lists, ``external`` implementations, SI arguments) build the small records here, so their parents can
ask for them by class too. A record that can be the first or last part of its parent keeps the span it
was built from, as a rule's location runs from the start of its first part to the end of its last
(``BehaviorExpressionRules.loc``); the lists that always sit between parentheses keep none.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, TypeVar

from coverage_engine.location import Location
from coverage_engine.parse import syntax as s
from coverage_engine.parse.lexer import Token
from coverage_engine.records import Record, record

T = TypeVar("T")


def token(children: Sequence[object], *kinds: str) -> Token:
    """The first token of terminal ``kinds`` (``"NAME"``, ``"STRING"`` …) among ``children``: a part
    the rule always has (missing, the grammar and the builder disagree)."""
    for child in children:
        if type(child) is Token and child.type in kinds:
            return child
    raise LookupError(f"no {' or '.join(kinds)} token among the rule's parts {children!r}")


def maybe_token(children: Sequence[object], *kinds: str) -> Token | None:
    """The first token of terminal ``kinds`` among ``children``; None when the optional part is absent."""
    for child in children:
        if type(child) is Token and child.type in kinds:
            return child
    return None


def tokens(children: Sequence[object], kind: str) -> list[Token]:
    """Every token of terminal ``kind`` among ``children``, in order (``NAME ("," NAME)*``)."""
    return [child for child in children if type(child) is Token and child.type == kind]


def node(children: Sequence[object], kind: type[T]) -> T:
    """The first value of class ``kind`` a sub-rule built among ``children``: a part the rule always has."""
    for child in children:
        if isinstance(child, kind):
            return child
    raise LookupError(f"no {kind.__name__} among the rule's parts {children!r}")


def maybe_node(children: Sequence[object], kind: type[T]) -> T | None:
    """The first value of class ``kind`` among ``children``; None when the optional part is absent."""
    for child in children:
        if isinstance(child, kind):
            return child
    return None


def nodes(children: Sequence[object], kind: type[T]) -> tuple[T, ...]:
    """Every value of class ``kind`` among ``children``, in order (``member+``, ``import_stmt*``)."""
    return tuple([child for child in children if isinstance(child, kind)])


def built(children: Sequence[object]) -> tuple[Any, ...]:
    """Every value a sub-rule built, in order: the children that are not tokens (``keep(expr)``'s expression
    is ``(constraint,) = built(children)``). Typed Any: which syntax nodes they are is the grammar's rule,
    which the type system does not see."""
    return tuple([child for child in children if type(child) is not Token])


# ---------------------------------------------------------------------------------------------- the
# values of the sub-rules that make no syntax node


@record
class Inherits(Record):
    """``inherits Parent`` of a struct, actor, action or scenario."""

    parent: s.QualifiedName


@record
class Default(Record):
    """``= expression``: the default value of a parameter, variable or method parameter."""

    value: s.Expression
    location: Location


@record
class WithBlock(Record):
    """``with:`` and its indented members (keeps, modifiers, ``until``)."""

    members: tuple[s.WithMember, ...]
    location: Location


@record
class ArgumentList(Record):
    """The arguments of a call, an invocation, a modifier or a composite, positional ones first."""

    arguments: tuple[s.Argument, ...]


def arguments_of(children: Sequence[object]) -> tuple[s.Argument, ...]:
    """The arguments among a rule's ``[arguments]`` part: () when the parentheses are empty."""
    for child in children:
        if type(child) is ArgumentList:
            return child.arguments
    return ()


@record
class MethodParams(Record):
    """The parameter list of a ``def`` or of an ``event``."""

    params: tuple[s.MethodParameter, ...]


@record
class ExternalImpl(Record):
    """``is external lib.function(arguments)``: the Python function a method calls."""

    function: s.QualifiedName
    arguments: tuple[s.Argument, ...]


@record
class SignedNumber(Record):
    """A number with an optional ``-``, as the SI arguments of a unit or physical type write it."""

    value: int | float
    location: Location


@record
class SiArgument(Record):
    """One ``name: number`` of ``SI(...)`` (``m: 1``, ``factor: 0.44704``)."""

    name: str
    value: int | float
    location: Location


@record
class SiArguments(Record):
    """The ``name: number`` list inside ``SI(...)``."""

    items: tuple[SiArgument, ...]


@record
class Refusal(Record):
    """A part the grammar accepts only to refuse it by name at its place (``event … as``, ``if …``)."""

    what: str
    location: Location


@record
class Marker(Record):
    """An optional part whose presence alone matters, to be refused at its place (``modifier … of …``,
    conditional inheritance, ``event … is <condition>``)."""

    location: Location
