"""A ball dropped in MuJoCo, driven step by step: ``--simulation examples.mujoco.sim:BallSimulation``.

The specification's ``SimulationInterface`` sample on a real engine: the model is loaded once with
``MjModel.from_xml_path`` (``setup``), every scenario starts from ``mj_resetData`` with its
parameters injected into ``reset`` by name, and each tick is one ``mj_step`` of 2 ms. Actions read
the simulation through ``kwargs['simulation']`` in their ``setup`` (see ``mujoco_drop/actions.py``).
"""

from __future__ import annotations

from pathlib import Path

from executor.runtime.simulation import SimulationInterface
from executor.simulations import engines

MODEL = Path(__file__).resolve().parent / "ball.xml"
BALL_RADIUS = 0.1  # metres, as in ball.xml


class BallSimulation(SimulationInterface):
    """The ball of ``ball.xml``, dropped from ``drop_height`` with a horizontal ``throw_speed``."""

    def __init__(self) -> None:
        self._mujoco = None
        self._model = None
        self._data = None

    @property
    def dt(self) -> float:
        return 0.002  # the model's timestep (500 Hz)

    def setup(self, **kwargs) -> None:
        mujoco = self._mujoco = engines.mujoco()
        self._model = mujoco.MjModel.from_xml_path(str(MODEL))
        self._data = mujoco.MjData(self._model)

    def reset(self, drop_height: float, throw_speed: float = 0.0, friction: float = 1.0) -> None:
        """Scenario parameters arrive by name, in SI units (metres, metres per second)."""
        mujoco = self._mujoco
        mujoco.mj_resetData(self._model, self._data)
        ball = self._model.geom("ball")
        ball.friction[0] = friction
        self._model.geom("floor").friction[0] = friction
        self._data.qpos[:3] = [0.0, 0.0, drop_height + BALL_RADIUS]  # free joint: x y z, then a quaternion
        self._data.qvel[:3] = [throw_speed, 0.0, 0.0]
        mujoco.mj_forward(self._model, self._data)

    def step(self) -> None:
        self._mujoco.mj_step(self._model, self._data)

    def get_observation(self) -> dict:
        """What actions may read: simulated time, the ball's position and whether it touches the floor."""
        data = self._data
        x, y, z = (float(v) for v in data.qpos[:3])
        return {"time": float(data.time), "x": x, "y": y, "height": z - BALL_RADIUS,
                "touching": data.ncon > 0}

    def shutdown(self) -> None:
        self._model = None
        self._data = None
