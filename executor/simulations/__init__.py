"""Simulation libraries: ``osc.pybullet``, ``osc.ros``, ``osc.nav2`` and ``osc.gazebo`` on real engines.

Each library is a folder with its ``lib_osc/<name>.osc`` declarations and the actions implementing
them, registered through the same entry points as a third-party library (``pyproject.toml``).
The engines are optional extras, imported only when an action or a simulation runs
(:mod:`executor.simulations.engines`):

``pybullet/``
    the PyBullet world (:class:`~executor.simulations.pybullet.world.World`), the step-based
    :class:`~executor.simulations.pybullet.simulation.PyBulletSimulation` and the ``osc.pybullet`` actions.
``navigation/``
    the engine-independent navigation core the ROS-free ``osc.ros``/``osc.nav2`` actions use:
    occupancy maps, costmap, planner, path follower, laser model, localisation.
``ros/``, ``nav2/``, ``gazebo/``
    the actions of those libraries, on the PyBullet world and the navigation core.

Nothing here is imported by the front end: finding a library's ``.osc`` file goes through
:mod:`executor.simulations.libraries`, which imports nothing heavy.
"""
