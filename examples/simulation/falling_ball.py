"""A tiny pure-Python step-based simulation for ``--simulation falling_ball.py:FallingBall``."""

from __future__ import annotations

from executor.runtime.simulation import SimulationInterface


class FallingBall(SimulationInterface):
    """A ball dropped from ``height`` metres; integrates its fall with a fixed step."""

    def __init__(self) -> None:
        self.height = 0.0
        self.velocity = 0.0
        self.gravity = 9.81
        self.steps = 0

    @property
    def dt(self) -> float:
        return 0.001  # 1 kHz

    def setup(self, **kwargs) -> None:
        self.logger = kwargs.get("logger")

    def reset(self, height: float, gravity: float = 9.81) -> None:
        """Parameters are injected by name from the scenario (overrides already applied)."""
        self.height, self.velocity, self.gravity, self.steps = height, 0.0, gravity, 0
        print(f"SIM reset: height={height} m, gravity={gravity} m/s2", flush=True)

    def step(self) -> None:
        self.steps += 1
        if self.height > 0.0:
            self.velocity += self.gravity * self.dt
            self.height = max(0.0, self.height - self.velocity * self.dt)

    def shutdown(self) -> None:
        print(f"SIM shutdown after {self.steps} steps, ball at {self.height:.2f} m", flush=True)
