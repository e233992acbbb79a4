"""``wait_for_landing``: an action that reads the step-based simulation through ``kwargs['simulation']``."""

from __future__ import annotations

import math

import py_trees

from executor.actions import ActionBase, ActionError


class WaitForLanding(ActionBase):
    """Running until the ball touches the floor; then stores when and how far, and succeeds."""

    def __init__(self):
        # variables arrive as handles (get_value/set_value), so the action can write them
        super().__init__(resolve_variable_reference_arguments_in_execute=False)
        self.simulation = None
        self.targets = {}

    def setup(self, **kwargs):
        self.simulation = kwargs.get("simulation")
        if self.simulation is None or not hasattr(self.simulation, "get_observation"):
            raise ActionError("needs the step-based simulation: --simulation examples.mujoco.sim:BallSimulation")

    def execute(self, landing_time="", landing_distance=""):
        self.targets = {key: handle for key, handle in (("time", landing_time), ("distance", landing_distance))
                        if hasattr(handle, "set_value")}

    def update(self) -> py_trees.common.Status:
        seen = self.simulation.get_observation()
        if not seen["touching"]:
            self.feedback_message = f"falling, {seen['height']:.3f} m above the floor at {seen['time']:.3f} s"
            return py_trees.common.Status.RUNNING
        distance = math.hypot(seen["x"], seen["y"])
        if "time" in self.targets:
            self.targets["time"].set_value(seen["time"])
        if "distance" in self.targets:
            self.targets["distance"].set_value(distance)
        self.feedback_message = f"landed at {seen['time']:.3f} s, {distance:.3f} m from below the start"
        self.logger.info(self.feedback_message)
        return py_trees.common.Status.SUCCESS
