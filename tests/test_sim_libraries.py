"""The simulation libraries are declared in three places that must agree: their ``lib_osc/*.osc`` files
(what scenarios may write), ``pyproject.toml``'s entry points (what the runtime looks up) and the
classes and functions of ``executor.simulations`` (what runs). An action or external method added to
one and not the others fails here, not in a user's scenario. No engine is needed: the modules import
PyBullet and MuJoCo only when an action runs."""

from __future__ import annotations

import importlib
import inspect
from importlib.metadata import entry_points
from pathlib import Path

import pytest
import tomllib

from coverage_engine.parse import syntax
from coverage_engine.parse.parser import parse_file
from coverage_engine.resolve.checks import RESERVED_ACTION_PARAMETERS
from coverage_engine.resolve.libraries import find_library
from executor.actions import ActionBase
from executor.actions.registry import ENTRY_POINT_GROUP

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = "executor.simulations."
LIBRARIES = {name: parse_file(find_library(name)) for name in ("osc.pybullet", "osc.ros", "osc.nav2", "osc.gazebo")}
DECLARED_ACTIONS = {d.name.dotted: d for unit in LIBRARIES.values() for d in unit.declarations
                    if isinstance(d, syntax.TypeDecl) and d.kind == "action"}


def pyproject_entry_points() -> dict[str, str]:
    """The entry points of pyproject.toml whose classes are in executor.simulations."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    return {name: target for name, target in project["project"]["entry-points"][ENTRY_POINT_GROUP].items()
            if target.startswith(PACKAGE)}


def test_every_declared_action_has_an_entry_point_and_no_more():
    assert len(DECLARED_ACTIONS) == 41
    assert set(pyproject_entry_points()) == set(DECLARED_ACTIONS)


def test_the_installed_entry_points_are_those_of_pyproject():
    installed = {ep.name: ep.value for ep in entry_points(group=ENTRY_POINT_GROUP) if ep.value.startswith(PACKAGE)}
    assert installed == pyproject_entry_points(), "reinstall the project (pip install -e .): its metadata is stale"


@pytest.mark.parametrize("name", sorted(DECLARED_ACTIONS))
def test_each_action_class_takes_what_its_library_declares(name):
    module_name, _, attribute = pyproject_entry_points()[name].partition(":")
    cls = getattr(importlib.import_module(module_name), attribute)
    assert issubclass(cls, ActionBase)
    declared = {n for member in DECLARED_ACTIONS[name].members if isinstance(member, syntax.ParameterDecl)
                for n in member.names}
    accepted: dict[str, inspect.Parameter] = {}
    takes_any = False
    for method in (cls.__init__, getattr(cls, "execute", None)):
        if method is None:
            continue
        for parameter in list(inspect.signature(method).parameters.values())[1:]:
            if parameter.kind is inspect.Parameter.VAR_KEYWORD:
                takes_any = True
            elif parameter.kind is not inspect.Parameter.VAR_POSITIONAL:
                accepted[parameter.name] = parameter
    assert takes_any or declared <= set(accepted), f"{name}: declared but not taken: {sorted(declared - set(accepted))}"
    required = {n for n, p in accepted.items() if p.default is inspect.Parameter.empty}
    assert required <= declared | set(RESERVED_ACTION_PARAMETERS), \
        f"{name}: required by the class but not declared: {sorted(required - declared)}"


def test_every_external_method_exists_and_takes_the_declared_arguments():
    methods = [member for unit in LIBRARIES.values() for d in unit.declarations if isinstance(d, syntax.TypeDecl)
               for member in d.members if isinstance(member, syntax.MethodDecl)]
    assert methods
    for method in methods:
        *module, function = method.external.parts
        target = getattr(importlib.import_module(".".join(module)), function)
        taken = list(inspect.signature(target).parameters)
        declared = [parameter.name for parameter in method.parameters]
        assert taken == declared, method.external.dotted
