"""MkDocs hook: the library part of the language reference, generated from our own ``.osc`` libraries.

``docs/language.md`` holds the marker ``<!-- osc-library-reference -->``; this hook replaces it with one
section per library (``osc.types``, ``osc.helpers``, ``osc.standard``, ``osc.robotics``): its actions and
modifiers with their parameters (type, default) and the comment written under each declaration, its
actors and structs, enums, physical types and units. The page cannot drift from what the resolver knows,
because it is read from the same files by the same parser.
"""

from __future__ import annotations

from pathlib import Path

MARKER = "<!-- osc-library-reference -->"
LIBRARIES = ("types", "helpers", "standard", "robotics")


def on_page_markdown(markdown: str, page, config, files) -> str:  # noqa: ARG001 - the MkDocs hook signature
    if MARKER not in markdown:
        return markdown
    return markdown.replace(MARKER, library_reference())


def library_reference() -> str:
    import coverage_engine
    from coverage_engine.parse.parser import parse_text

    folder = Path(coverage_engine.__file__).parent / "osc"
    parts = []
    for name in LIBRARIES:
        path = folder / f"{name}.osc"
        text = path.read_text(encoding="utf-8")
        parts.append(_library(f"osc.{name}", parse_text(text, str(path)), text.splitlines()))
    return "\n".join(parts)


def _library(title: str, unit, lines: list[str]) -> str:
    from coverage_engine.parse import syntax

    out = [f"### `import {title}`", ""]
    kinds: dict[str, list] = {}
    for decl in unit.declarations:
        if isinstance(decl, syntax.TypeDecl):
            kinds.setdefault(decl.kind, []).append(decl)
        elif isinstance(decl, syntax.EnumDecl):
            kinds.setdefault("enum", []).append(decl)
        elif isinstance(decl, syntax.UnitDecl):
            kinds.setdefault("unit", []).append(decl)
        elif isinstance(decl, syntax.PhysicalTypeDecl):
            kinds.setdefault("physical type", []).append(decl)
    if not kinds:
        return "\n".join([*out, "Nothing but imports of the other libraries.", ""])
    for kind in ("action", "modifier", "actor", "struct"):
        for decl in kinds.get(kind, []):
            out += _type_section(kind, decl, lines)
    if kinds.get("enum"):
        out += ["| enum | values |", "|---|---|"]
        out += [f"| `{e.name}` | {', '.join(f'`{m.name}`' for m in e.members)} |" for e in kinds["enum"]]
        out.append("")
    if kinds.get("physical type"):
        out += ["Physical types: " + ", ".join(f"`{p.name}`" for p in kinds["physical type"]) + ".", ""]
    if kinds.get("unit"):
        out += ["| unit | of | factor | offset |", "|---|---|---|---|"]
        out += [f"| `{u.name}` | `{u.physical_type}` | {_number(u.factor, 1)} | {_number(u.offset, 0)} |"
                for u in kinds["unit"]]
        out.append("")
    return "\n".join(out)


def _type_section(kind: str, decl, lines: list[str]) -> list[str]:
    from coverage_engine.parse import syntax

    name = decl.name.dotted
    parent = f" (inherits `{decl.parent.dotted}`)" if decl.parent is not None else ""
    out = [f"**{kind} `{name}`**{parent}", ""]
    doc = _comment_after(lines, decl.location.line)
    if doc:
        out += [doc, ""]
    parameters = [m for m in decl.members if isinstance(m, syntax.ParameterDecl)]
    if parameters:
        out += ["| parameter | type | default |", "|---|---|---|"]
        for member in parameters:
            type_name = ("list of " if member.type.is_list else "") + member.type.name.dotted
            default = _source(lines, member.default.location) if member.default is not None else "—"
            out += [f"| `{', '.join(member.names)}` | `{type_name}` | {default} |"]
        out.append("")
    events = [m for m in decl.members if isinstance(m, syntax.EventDecl)]
    if events:
        out += ["Events: " + ", ".join(f"`{e.name}`" for e in events) + ".", ""]
    return out


def _comment_after(lines: list[str], line: int) -> str:
    """The ``#`` comment lines right under a declaration's first line, joined."""
    found = []
    for text in lines[line:]:
        stripped = text.strip()
        if not stripped.startswith("#"):
            break
        found.append(stripped.lstrip("#").strip())
    return " ".join(found)


def _source(lines: list[str], location) -> str:
    if location.line == location.end_line:
        text = lines[location.line - 1][location.column - 1:location.end_column - 1]
        return f"`{text}`" if text else "—"
    return "(several lines)"


def _number(value: float | None, default: float) -> str:
    return f"{default if value is None else value:g}"
