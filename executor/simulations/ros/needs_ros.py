"""The ``osc.ros`` actions that need a ROS graph: declared so scenarios resolve, failing when they run."""

from __future__ import annotations

import py_trees

from executor.actions.base import ActionBase, ActionError


class NeedsRos(ActionBase):
    """Topics, services, actions, lifecycle nodes and launch files exist only in a ROS 2 system."""

    def __init__(self) -> None:
        super().__init__()

    def execute(self, **arguments: object) -> None:
        """Accept every declared argument."""

    def update(self) -> py_trees.common.Status:
        raise ActionError("needs ROS: this ROS-free backend has no ROS graph (topics, services, actions, "
                          "lifecycle nodes, launch files); run the scenario with the ROS runner instead")
