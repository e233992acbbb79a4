"""``osc.gazebo`` on the PyBullet world: spawn, delete, exists, wait for the simulation."""
