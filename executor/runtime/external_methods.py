"""Python side of the ``osc.helpers`` external methods ``common`` (run-time directories) and ``random``.

``helpers.osc`` declares them as ``is external osc.helpers.<function>()``; :func:`provide` serves that
name from this module, so the library names no module of the runtime. ``common.get_output_directory()``
and ``common.get_scenario_file_directory()`` return absolute paths of the running scenario; the
runtime publishes them with :func:`set_directories` before each run.
"""

from __future__ import annotations

import os

from coverage_engine.resolve.evaluate import provide_module

#: The module name ``helpers.osc`` gives its external methods.
HELPERS_MODULE = "osc.helpers"

_directories: dict[str, str | None] = {"scenario_file": None, "output": None}


def set_directories(scenario_file_directory: str | None, output_directory: str | None) -> None:
    """Called by the runtime before a scenario starts."""
    _directories["scenario_file"] = os.path.abspath(scenario_file_directory) if scenario_file_directory else None
    _directories["output"] = os.path.abspath(output_directory) if output_directory else None


def get_scenario_file_directory() -> str:
    """Absolute directory of the scenario file being run."""
    return _directories["scenario_file"] or os.getcwd()


def get_output_directory() -> str:
    """Absolute output directory of the running scenario (the working directory without ``-o``)."""
    return _directories["output"] or os.getcwd()


# --------------------------------------------------------------------------------------------------
# ``random``: values drawn when the action starts (seed with ``random.seed(n)`` for repeatable runs)


def seed(seed_value: int = 0) -> None:
    """Seed the generator used by the other ``random`` methods."""
    import random

    random.seed(seed_value)


def get_float(min_val: float, max_val: float) -> float:
    """A float in ``[min_val, max_val]``."""
    import random

    return random.uniform(min_val, max_val)


def get_int(min_val: int, max_val: int) -> int:
    """An int in ``[min_val, max_val]`` (both included)."""
    import random

    return random.randint(int(min_val), int(max_val))


def get_random_list_element(elements_list: list) -> object:
    """One element of the list (None for an empty list)."""
    import random

    return random.choice(elements_list) if elements_list else None


def provide() -> None:
    """Serve the external methods of ``osc.helpers`` from this module (before a scenario runs)."""
    provide_module(HELPERS_MODULE, {
        "get_scenario_file_directory": get_scenario_file_directory,
        "get_output_directory": get_output_directory,
        "seed": seed,
        "get_float": get_float,
        "get_int": get_int,
        "get_random_list_element": get_random_list_element,
    })
