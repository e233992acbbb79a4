"""The built-ins are declared in three places that must agree: ``osc/helpers.osc`` (what scenarios may
write), ``pyproject.toml``'s entry points (what plugins see) and the classes and functions of
``executor`` (what runs). Adding an action, a modifier or an external method to one and not the
others fails here, not in a user's scenario."""

from __future__ import annotations

import inspect
from importlib.metadata import entry_points
from pathlib import Path

import pytest
import tomllib

from coverage_engine.location import Location
from coverage_engine.parse import syntax
from coverage_engine.parse.parser import parse_file
from coverage_engine.resolve import evaluate, model
from coverage_engine.resolve.checks import RESERVED_ACTION_PARAMETERS
from coverage_engine.resolve.libraries import find_library
from executor.actions import ActionBase
from executor.actions.registry import BUILTIN_ACTIONS, BUILTIN_MODIFIERS, ENTRY_POINT_GROUP
from executor.runtime import external_methods

ROOT = Path(__file__).resolve().parent.parent
HELPERS = parse_file(find_library("osc.helpers"))


def declarations(kind: str) -> dict[str, syntax.TypeDecl]:
    return {d.name.dotted: d for d in HELPERS.declarations if isinstance(d, syntax.TypeDecl) and d.kind == kind}


def declared_parameters(decl: syntax.TypeDecl) -> dict[str, bool]:
    """Parameter name -> whether it has a default."""
    return {name: m.default is not None for m in decl.members if isinstance(m, syntax.ParameterDecl)
            for name in m.names}


def test_pyproject_entry_points_are_the_built_in_actions():
    """Besides the built-ins the group holds the simulation libraries' actions (tests/test_sim_libraries.py)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    group = project["project"]["entry-points"][ENTRY_POINT_GROUP]
    assert {name: target for name, target in group.items()
            if not target.startswith("executor.simulations.")} == BUILTIN_ACTIONS


def test_the_installed_entry_points_are_those_of_pyproject():
    installed = {ep.name: ep.value for ep in entry_points(group=ENTRY_POINT_GROUP) if ep.name in BUILTIN_ACTIONS}
    assert installed == BUILTIN_ACTIONS, "reinstall the project (pip install -e .): its metadata is stale"


def test_helpers_declares_exactly_the_built_in_actions_and_modifiers():
    assert set(declarations("action")) == set(BUILTIN_ACTIONS)
    assert set(declarations("modifier")) == set(BUILTIN_MODIFIERS)


@pytest.mark.parametrize("name", sorted(BUILTIN_ACTIONS))
def test_each_action_class_takes_what_helpers_declares(name):
    module_name, _, attribute = BUILTIN_ACTIONS[name].partition(":")
    cls = getattr(__import__(module_name, fromlist=[attribute]), attribute)
    assert issubclass(cls, ActionBase)
    declared = declared_parameters(declarations("action")[name])
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
    assert takes_any or set(declared) <= set(accepted), f"{name}: declared but not taken: " \
                                                        f"{sorted(set(declared) - set(accepted))}"
    required = {n for n, p in accepted.items() if p.default is inspect.Parameter.empty}
    assert required <= set(declared) | set(RESERVED_ACTION_PARAMETERS), \
        f"{name}: required by the class but not declared: {sorted(required - set(declared))}"


def test_every_external_method_of_helpers_is_provided_by_the_runtime():
    external_methods.provide()
    declared = [method for decl in declarations("struct").values() for method in decl.members
                if isinstance(method, syntax.MethodDecl)]
    assert declared
    for method in declared:
        *module, function = method.external.parts
        assert ".".join(module) == external_methods.HELPERS_MODULE, method.external.dotted
        signature = model.ExternalMethod(method.name, ".".join(module), function, (), None, Location("t", 1, 1))
        assert evaluate.external_function(signature) is getattr(external_methods, function)
