"""``osc.nav2`` on the PyBullet navigation backend.

``actions``
    ``init_nav2``, ``nav_to_pose``, ``nav_through_poses``, ``follow_waypoints`` on the
    :mod:`~executor.simulations.navigation` stack.
"""
