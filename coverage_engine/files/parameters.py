"""Scenario parameter files: read their YAML documents, and write a template of all overridable parameters.

Several documents in one file (``---``) mean several runs: the executor runs every scenario once per
document. The template holds each scenario's overridable parameters with their current values in SI
base units, structs as mappings and enums by name, so that reading it back changes nothing.
"""

from __future__ import annotations

from pathlib import Path

from coverage_engine.errors import ParameterFileError
from coverage_engine.location import Location
from coverage_engine.resolve.model import EnumValue, ScenarioFile


def read_parameter_documents(path: str | Path) -> list[dict]:
    """The non-empty documents of a parameter file, in order; a file without any is one empty document
    (the scenarios run once with their defaults). Empty documents (a leading or trailing ``---``) add no run.

    A key written twice in one mapping is an error at its second place (PyYAML alone keeps the last).
    """
    import yaml

    path = Path(path)
    whole_file = Location.whole_file(str(path))
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ParameterFileError("scenario parameter file not found", whole_file) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ParameterFileError(f"cannot read scenario parameter file: {exc}", whole_file) from exc
    from coverage_engine.yaml_bounds import SAFE_LOADER, YamlLimitError, load_all_bounded, with_unique_keys

    try:
        documents = list(load_all_bounded(text, with_unique_keys(SAFE_LOADER)))
    except YamlLimitError as exc:           # too big, an alias bomb, or a key written twice (DuplicateKeyError)
        lines = text.splitlines()
        line = lines[exc.line - 1] if 0 < exc.line <= len(lines) else None
        raise ParameterFileError(str(exc), Location.at(str(path), exc.line, exc.column),
                                 source_line=line) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = Location(str(path), mark.line + 1, mark.column + 1) if mark is not None else whole_file
        problem = getattr(exc, "problem", None) or str(exc)
        line = text.splitlines()[mark.line] if mark is not None and mark.line < len(text.splitlines()) else None
        raise ParameterFileError(f"invalid YAML: {problem}", where, source_line=line) from exc
    result: list[dict] = []
    for index, doc in enumerate(documents):
        if doc is None or doc == {}:
            continue              # a leading or trailing '---', or an empty document, adds no run
        if not isinstance(doc, dict):
            raise ParameterFileError(f"document {index + 1} must be a mapping of scenario names to "
                                     f"parameters, got {type(doc).__name__}", whole_file)
        result.append(doc)
    return result or [{}]


def template_values(scenario_file: ScenarioFile) -> dict[str, dict[str, object]]:
    """Scenario name → overridable parameter name → current value, as plain YAML data."""
    return {s.name: {p.name: _plain(p.value) for p in s.parameters if p.overridable}
            for s in scenario_file.scenarios}


def _plain(value: object) -> object:
    if isinstance(value, EnumValue):
        return value.name
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def write_parameter_template(scenario_path: str | Path, template_path: str | Path) -> None:
    """Write the template for ``scenario_path`` to ``template_path``; never overwrites an existing file."""
    import yaml

    from coverage_engine.files.loader import load_scenario_file

    target = Path(template_path)
    if target.exists():
        raise ParameterFileError("file exists; not overwriting it (remove it or choose another name)",
                                 Location.whole_file(str(target)))
    model = load_scenario_file(scenario_path)
    text = yaml.safe_dump(template_values(model), sort_keys=False, default_flow_style=False, allow_unicode=True)
    try:
        with open(target, "x", encoding="utf-8") as handle:
            handle.write(text)
    except FileExistsError:
        raise ParameterFileError("file exists; not overwriting it", Location.whole_file(str(target))) from None
    except OSError as exc:
        raise ParameterFileError(f"cannot write template: {exc.strerror}", Location.whole_file(str(target))) from exc
