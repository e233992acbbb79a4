"""Import the optional physics engines, with a message naming the extra that installs them.

The engines are optional extras of the distribution (``pip install 'scenario-coverage[pybullet]'``,
``[mujoco]``, ``[sim]`` for both). Nothing imports them at module level: an action or a simulation
calls :func:`pybullet` / :func:`mujoco` when it first needs the engine, so a run without the
extra fails only where an engine is really used, with :class:`EngineMissingError` saying what to
install (an :class:`~executor.actions.base.ActionError`, so the scenario fails with that message).

PyBullet's C code prints to the process's standard output (its build date on import, warnings
about URDF links without inertia); :func:`native_output_silenced` keeps those lines out of the
scenario log and ``test.xml``.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import sys
from collections.abc import Iterator
from types import ModuleType
from typing import TYPE_CHECKING

from executor.actions.base import ActionError

if TYPE_CHECKING:
    from typing import Any, TypeAlias

    import numpy as np
    from numpy.typing import NDArray

    # The arrays of the navigation core, for annotations only: numpy's own type information checks
    # what is done with them, while numpy itself is imported when an action first needs it.
    BoolArray: TypeAlias = NDArray[np.bool_]
    FloatArray: TypeAlias = NDArray[np.float64]
    IntArray: TypeAlias = NDArray[np.integer[Any]]
    RandomGenerator: TypeAlias = np.random.Generator


class EngineMissingError(ActionError):
    """A physics engine the scenario needs is not installed."""


#: module name -> (extra that installs it, what it is)
_EXTRAS = {
    "pybullet": ("pybullet", "the PyBullet physics engine"),
    "pybullet_data": ("pybullet", "PyBullet's model data"),
    "numpy": ("pybullet", "numpy"),
    "mujoco": ("mujoco", "the MuJoCo physics engine"),
}


def require(module: str) -> ModuleType:
    """Import ``module`` (an engine), or raise :class:`EngineMissingError` naming its extra.

    The engines ship no type information (numpy does, see the array types above), so their
    functions and constants are untyped (``Any``) to the type checker: the classes that wrap them
    (:class:`~executor.simulations.pybullet.world.World`) give the rest of the code typed methods.
    """
    try:
        with native_output_silenced():
            return importlib.import_module(module)
    except ImportError as exc:
        extra, what = _EXTRAS.get(module, (module, module))
        raise EngineMissingError(
            f"{what} is not installed (Python module '{module}'): install the extra with "
            f"pip install 'scenario-coverage[{extra}]' (or '.[{extra}]' in a checkout)") from exc


def pybullet() -> ModuleType:
    """The ``pybullet`` module."""
    return require("pybullet")


def pybullet_data_path() -> str:
    """The folder of the models shipped with pybullet (``plane.urdf``, ``husky/husky.urdf``)."""
    return require("pybullet_data").getDataPath()


def numpy() -> ModuleType:
    """The ``numpy`` module (installed with the ``pybullet`` and ``mujoco`` extras)."""
    return require("numpy")


def mujoco() -> ModuleType:
    """The ``mujoco`` module."""
    return require("mujoco")


@contextlib.contextmanager
def native_output_silenced() -> Iterator[None]:
    """Send what C code writes to file descriptors 1 and 2 to ``/dev/null`` for the block.

    Python's own streams are flushed first, so nothing of ours is lost or reordered. Where the
    descriptors cannot be redirected (no real file behind them) the block runs unchanged.
    """
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = (os.dup(1), os.dup(2))
    except (OSError, ValueError, AttributeError):
        yield
        return
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(devnull, 1)
            os.dup2(devnull, 2)
        finally:
            os.close(devnull)
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        os.close(saved[0])
        os.close(saved[1])
