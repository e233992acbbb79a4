"""``osc.gazebo`` on the PyBullet world: spawn, delete, exists, wait for the simulation.

``actions``
    the library's actions (``world_name`` is accepted and ignored).
``models``
    what a model reference names, and the box that stands in for a model PyBullet cannot load.
"""
