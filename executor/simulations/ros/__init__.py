"""``osc.ros`` without ROS: the robot actions on the PyBullet navigation backend, the rest "needs ROS".

``actions``
    the actions that work on the simulated robot (``tf_close_to``, ``odometry_distance_traveled``,
    ``set_node_parameter``).
``recording``
    ``bag_record``: simulated topics as JSON lines.
``messages``
    the library's external methods (``msg_conversion``, ``ament``).
``needs_ros``
    the actions that need a ROS graph: declared so scenarios resolve, failing when they run.
"""
