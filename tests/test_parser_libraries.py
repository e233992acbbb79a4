"""Library discovery through the entry-point group, and the contents of our standard libraries."""

from __future__ import annotations

import pytest

from coverage_engine.errors import ImportResolutionError
from coverage_engine.parse import syntax as s
from coverage_engine.parse.parser import parse_file
from coverage_engine.resolve.libraries import OWN_LIBRARIES, _registered, find_library


@pytest.mark.parametrize("name", OWN_LIBRARIES)
def test_own_libraries_are_found_and_registered(name):
    path = find_library(f"osc.{name}")
    assert path.name == f"{name}.osc" and path.is_file()
    assert name in _registered()  # pyproject.toml registers them under the same group


@pytest.mark.parametrize("name", ["osc.nope", "helpers", "osc.", "other.helpers"])
def test_unknown_or_malformed_names(name):
    with pytest.raises(ImportResolutionError, match="nope|osc.<library-name>|helpers|osc"):
        find_library(name)


def test_helpers_declares_the_reference_api():
    unit = parse_file(find_library("osc.helpers"))
    by_name = {d.name.dotted: d for d in unit.declarations if isinstance(d, s.TypeDecl)}
    for action in ("log", "run_process", "compare", "increment", "decrement", "process_log_check"):
        assert by_name[action].kind == "action"
    for modifier in ("timeout", "repeat", "retry", "inverter", "failure_is_running", "failure_is_success",
                     "running_is_failure", "running_is_success", "success_is_failure", "success_is_running"):
        assert by_name[modifier].kind == "modifier"
    run = {m.names[0]: m for m in by_name["run_process"].members}
    assert run["shutdown_timeout"].default.unit == "s" and run["wait_for_shutdown"].default.value is True
    assert {m.name for m in by_name["random"].members} == {"seed", "get_float", "get_int", "get_random_string"}


def test_types_has_units_with_offsets_and_geometry():
    unit = parse_file(find_library("osc.types"))
    units = {d.name: d for d in unit.declarations if isinstance(d, s.UnitDecl)}
    assert units["celsius"].offset == 273.15 and units["kmph"].physical_type == "speed"
    for name in ("m", "cm", "mm", "km", "s", "ms", "min", "hour", "mps", "kmph", "rad", "deg", "kg", "N", "K"):
        assert name in units
    structs = {d.name.dotted for d in unit.declarations if isinstance(d, s.TypeDecl)}
    assert {"position_3d", "orientation_3d", "pose_3d", "translational_velocity_3d", "osc_actor"} <= structs
