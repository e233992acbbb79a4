"""The Husky of ``pybullet_data`` as a differential-drive robot for the navigation stack.

The Husky is skid-steered: four wheels, the two on a side driven alike. With isotropic friction
PyBullet's skidding wheels make turns erratic (the body hops and drifts), so the wheels get less
friction along their axles than along their rolling direction (anisotropic friction, as a
skid-steer's tyres effectively have); then a velocity command ``(v, w)`` turned into wheel speeds
for a track :data:`EFFECTIVE_TRACK` gives about the commanded motion, and the navigation's
controller closes the loop on the pose. Its links are put in their own collision filter group
so the robot's laser does not see the robot.

Turning in place, a skid-steer does not pivot about its centre (here the rear wheels, carrying
more weight, grip more): the body slides sideways. Its odometry therefore reports the planar
velocity in all three directions (forward, sideways, yaw rate), as the fusion of wheel encoders
and an IMU on a well-tuned robot approximately does; the stack adds its noise.
"""

from __future__ import annotations

from collections.abc import Sequence

from executor.actions.base import ActionError
from executor.simulations.pybullet.world import Vec3, World

MODEL = "husky/husky.urdf"
WHEEL_RADIUS = 0.1651        # m, from the URDF
EFFECTIVE_TRACK = 0.7        # m: the real track is 0.571 m; skidding turns need a little more
AXLE_FRICTION = 0.3          # friction along the axle relative to the rolling direction
WHEEL_TORQUE = 50.0          # N m per wheel
ROBOT_GROUP = 0x10           # collision filter group of robots (excluded from their lasers)
LEFT, RIGHT = ("front_left_wheel", "rear_left_wheel"), ("front_right_wheel", "rear_right_wheel")


class HuskyBase:
    """A Husky body in ``world`` under ``name``, driven by ``(linear, angular)`` velocity commands."""

    #: the disk around the centre the robot needs free (between its half width 0.34 m and half length 0.5 m)
    radius = 0.45
    front = 0.5
    half_width = 0.35

    def __init__(self, world: World, name: str, pose: Vec3) -> None:
        self.world = world
        self.name = name
        path = world.find_model(MODEL)
        if path is None:
            raise ActionError(f"'{MODEL}' is missing from pybullet_data")
        self.body = world.load_urdf(name, path, (pose[0], pose[1], 0.02), (0.0, 0.0, pose[2]))
        joints = {joint.name: joint.index for joint in world.joints(self.body)}
        try:
            self._wheels = [joints[n] for n in LEFT + RIGHT]
        except KeyError as exc:
            raise ActionError(f"{MODEL} has no wheel joint {exc}") from None
        world.set_collision_group(self.body, ROBOT_GROUP)
        for wheel in self._wheels:
            world.set_anisotropic_friction(self.body, wheel, (1.0, AXLE_FRICTION, 1.0))
        self.drive(0.0, 0.0)

    def true_pose(self) -> Vec3:
        """``(x, y, yaw)`` of the base frame (midway between the axles)."""
        return self.world.pose_2d(self.body)

    def measured_velocity(self) -> Vec3:
        """``(forward, sideways, yaw rate)`` of the base in its own frame."""
        return self.world.velocity_2d(self.body)

    def drive(self, linear: float, angular: float) -> None:
        left = (linear - angular * EFFECTIVE_TRACK / 2.0) / WHEEL_RADIUS
        right = (linear + angular * EFFECTIVE_TRACK / 2.0) / WHEEL_RADIUS
        self.world.drive_joints(self.body, self._wheels, [left, left, right, right], [WHEEL_TORQUE] * 4)

    def ray_cast(self, starts: Sequence[Sequence[float]], ends: Sequence[Sequence[float]]) -> list[float]:
        return self.world.ray_cast(starts, ends, ignore_group=ROBOT_GROUP)
