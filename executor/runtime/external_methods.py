"""Python side of the ``osc.helpers`` external methods that need run-time state (``common``).

``common.get_output_directory()`` and ``common.get_scenario_file_directory()`` return absolute paths
of the running scenario; the runtime publishes them with :func:`set_directories` before each run.
"""

from __future__ import annotations

import os

_directories = {"scenario_file": None, "output": None}


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
