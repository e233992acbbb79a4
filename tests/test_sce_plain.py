"""The YAML-free reader of our own ``.sce`` shape gives what YAML gives, or steps aside.

The reference is PyYAML itself (the safe loader): for every text, ``load_plain`` either returns None
(the caller then uses YAML) or exactly the mapping PyYAML reads. Files as the writer makes them take
the short way; hand-edited or unusual ones (mutated at random here) never get a different meaning.
"""

from __future__ import annotations

import yaml
from hypothesis import given, settings
from text_mutations import mutated

from coverage_engine.files.sce import parse_sce
from coverage_engine.files.sce_plain import load_plain
from coverage_engine.files.sce_writer import render_sce

MODEL = ("\n\nimport osc.helpers\n\nscenario s:\n    v: float = 1.0 with:\n        keep(it == 2.5)\n"
         "    do serial:\n        log('x  #  y')\n\n\n")
VALUES = ["a", "it's", 'say "hi"', "back\\slash", "tab\there", "ünï", "line\nbreak", "\x85nel", "", "  pad  ",
          0, -7, 123456789012345678901, 2.5, -0.0, 1e-05, 1e300, float("inf"), float("nan"), True, False, None,
          "012", "1_000", "1.5e3", "yes", "null", "~", "#x"]


def sce_texts() -> list[str]:
    texts = [render_sce("s.osc", "0" * 64, ".", "s", i, {"s.v": value, "s.w": 1}, {}, MODEL)
             for i, value in enumerate(VALUES)]
    texts.append(render_sce("s.osc", "0" * 64, ".", "s", 1, {"s.v": 1}, {}, MODEL, parameters={"s": {"v": 1}}))
    texts.append(render_sce("s.osc", "0" * 64, ".", "s", 2, {}, {}, MODEL))
    texts.append(render_sce("s.osc", "0" * 64, ".", "s", 3, {"s.v": 1}, {}, "scenario s:\n    do serial:\n"
                            "        log('\u2028')\n"))                       # a model YAML must quote
    return texts


def same_as_yaml(text: str) -> dict | None:
    plain = load_plain(text)
    try:
        expected = yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except yaml.YAMLError:
        assert plain is None, text          # YAML refuses it: the short way must not accept it
        return None
    if plain is not None:
        assert plain == expected and [type(v) for v in plain.get("assignment", {}).values()] == \
            [type(v) for v in expected["assignment"].values()], text
    return plain


def test_files_as_written_are_read_the_short_way_with_yaml_s_meaning():
    texts = sce_texts()
    short = [text for text in texts if same_as_yaml(text) is not None]
    # the plain values (strings without escapes, our ints and decimal floats, booleans) take the short way
    assert len(short) >= 15
    plain_ones = {0: "a", 1: "it's", 5: "ünï", 8: "", 10: 0, 11: -7, 13: 2.5, 14: -0.0, 19: True, 20: False}
    for index, value in plain_ones.items():
        data = load_plain(texts[index])
        assert data is not None and data["assignment"]["s.v"] == value, (index, value)
    # parameters (a flow mapping), escapes, exponents, inf/nan and a quoted model go to YAML
    for index in (2, 3, 6, 7, 15, 16, 17, 18, 21, len(texts) - 1, len(texts) - 3):
        assert load_plain(texts[index]) is None, index
    document = parse_sce(texts[0], "/tmp/v0.sce")
    assert document.text.endswith("log('x  #  y')\n") and document.assignment == {"s.v": "a", "s.w": 1}


def test_near_misses_of_our_shape_are_left_to_yaml():
    # each is read by YAML another way than a line-by-line reading would suggest
    for text in ("format_version: 1\nassignment:\nmodel: |2\n  x\n# end\n",   # assignment is null
                 "format_version: 1\nmodel: |2\n  x",                         # no last line break
                 "format_version: 1\nyes: 1\nmodel: |2\n  x\n# end\n",        # the key is True
                 "format_version: 1\nnull: 1\nmodel: |2\n  x\n# end\n",
                 "format_version: 1\n1_0: 1\nmodel: |2\n  x\n# end\n"):
        assert load_plain(text) is None, text
        same_as_yaml(text)


PIECES = ["\n", ": ", "  ", " ", "#", '"', "\\", "\t", "\r", "|", "|2", "{}", "0", "1.", "e5", "true", "~", "\x85",
          "model: |2\n", "assignment:\n", '  "k": 1\n', "\n  x\n", "yes: 1\n", "null", "1_0"]


@settings(max_examples=400, deadline=2000)
@given(text=mutated(sce_texts(), PIECES))
def test_any_text_is_read_as_yaml_reads_it_or_left_to_yaml(text):
    same_as_yaml(text)
