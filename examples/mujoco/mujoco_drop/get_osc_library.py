"""Entry point of group ``scenario_execution.osc_libraries``: ``import osc.mujoco_drop``."""


def get_mujoco_drop_library():
    """``(package, file name)``: the file is ``<package>/lib_osc/<file name>``."""
    return "mujoco_drop", "mujoco_drop.osc"
