"""Entry point of group ``scenario_execution.osc_libraries``: where the library's .osc file is."""


def get_example_library():
    """``(package, file name)``: the file is ``<package>/lib_osc/<file name>``."""
    return "example_library", "example.osc"
