"""The engine-independent navigation core that the ROS-free ``osc.ros`` and ``osc.nav2`` actions run on.

``maps`` / ``images``
    occupancy maps (the ROS ``map_server`` YAML and its PGM or PNG image) and their grid geometry.
``laser``
    a 2-D laser scanner over the engine's ray casting, and the scan change used for fault injection.
``localization``
    odometry dead reckoning, or a particle filter on a known map (AMCL).
``costmap`` / ``planner`` / ``controller``
    what the robot sees, A* over it, and the path follower of a differential-drive robot.
``stack``
    one robot's stack of all of the above, with its goals; ``parameters`` its simulated nodes' parameters.
"""
