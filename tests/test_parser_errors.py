"""Parse errors: our error types, positions, messages in user words, the hint table, unsupported features."""

from __future__ import annotations

import pytest

from coverage_engine.errors import OscError, OscSyntaxError, UnsupportedFeatureError
from coverage_engine.parse.parser import parse_file, parse_text
from coverage_engine.parse.syntax_errors import HINTS


def error_of(text: str) -> OscError:
    with pytest.raises(OscError) as info:
        parse_text(text, "bad.osc")
    return info.value


@pytest.mark.parametrize(("label", "snippet"), [(lbl, s) for lbl, snippets in HINTS.items() for s in snippets])
def test_every_hint_snippet_fails_with_its_own_hint(label, snippet):
    err = error_of(snippet)
    assert isinstance(err, OscSyntaxError) and err.location is not None
    assert err.hint == label


def test_message_location_and_caret():
    err = error_of("scenario test:\n    do serial:\n        log('x'\n    wait\n")
    assert isinstance(err, OscSyntaxError)
    assert "_NL" not in err.message and "RPAR" not in err.message
    rendered = err.render()
    assert rendered.startswith(f"bad.osc:{err.location.line}:{err.location.column}: error: ")
    assert "^" in rendered.splitlines()[2]


def test_missing_colon_points_at_the_end_of_the_header():
    err = error_of("import osc.helpers\nscenario test\n    do log('x')\n")
    assert (err.location.line, err.location.column) == (2, 14)
    assert err.message.startswith("unexpected indentation")
    assert err.hint is not None and "':'" in err.hint


def test_inconsistent_dedent_has_a_position():
    err = error_of("scenario a:\n    do serial:\n        log()\n      log()\n")
    assert (err.location.line, err.location.column) == (4, 7)
    assert "indentation" in err.message


@pytest.mark.parametrize(("text", "feature", "line", "column"), [
    ("scenario t:\n    do serial:\n        cover(x)\n", "cover() in a behaviour", 3, 9),
    ("struct b:\n    p: int = 1 with:\n        remove_default(it.p)\n", "remove_default()", 3, 9),
    ("scenario t:\n    var x: time = sample(a.b, @e.start)\n", "sample()", 2, 19),
    ("scenario t:\n    event e is every(1s)\n", "every()", 2, 16),
    ("scenario t:\n    on @e:\n        emit x\n", "on @event", 2, 5),
    ("namespace foo\n", "namespaces", 1, 1),
    ("enum e: [a]\nextend e: [b]\n", "extending an enum", 2, 1),
    ("actor a inherits b(x == true)\n", "conditional inheritance", 1, 19),
    ("modifier a.b\n", "actor modifiers", 1, 10),
    ("modifier m of b\n", "modifier ... of", 1, 12),
    ("global t: int = foo[2]\n", "element access", 1, 17),
    ("global t: int = foo.as(int)\n", "type casts", 1, 17),
    ("struct s:\n    def f() -> int is undefined\n", "undefined", 2, 23),
])
def test_unsupported_features_are_rejected_where_they_stand(text, feature, line, column):
    err = error_of(text)
    assert isinstance(err, UnsupportedFeatureError)
    assert err.message.startswith("not supported: ") and feature in err.message
    assert (err.location.line, err.location.column) == (line, column)


def test_positional_after_named_argument():
    err = error_of("scenario a:\n    do log(msg: 'a', 'b')\n")
    assert "positional" in err.message and err.location.column == 22


def test_unreadable_files(tmp_path):
    with pytest.raises(OscError, match="missing.osc"):
        parse_file(tmp_path / "missing.osc")
    bad = tmp_path / "latin1.osc"
    bad.write_bytes(b"global s: string = '\xe9'\n")
    with pytest.raises(OscError, match="UTF-8"):
        parse_file(bad)


@pytest.mark.parametrize(("text", "declarations"), [
    ("", 0), ("\n\n", 0), ("# only a comment", 0), ("\ufeffscenario a:\n    do log()\n", 1)])
def test_degenerate_inputs_parse(text, declarations):
    assert len(parse_text(text, "x.osc").declarations) == declarations


@pytest.mark.parametrize("text", ["(" * 3000, "global x: int = " + "9" * 5000 + "\n", "\x00", "|", "\'\'\'"])
def test_hostile_inputs_give_our_errors(text):
    with pytest.raises(OscError) as info:
        parse_text(text, "x.osc")
    assert info.value.location is not None


@pytest.mark.parametrize("text", ["global x: int = " + "(" * 2000 + "1" + ")" * 2000 + "\n", "\\"])
def test_hostile_but_valid_inputs_parse(text):
    parse_text(text, "x.osc")
