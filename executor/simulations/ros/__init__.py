"""``osc.ros`` without ROS: the robot actions on the PyBullet navigation backend, the rest "needs ROS"."""
