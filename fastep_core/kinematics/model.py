"""What the planning code may assume of a robot model and its controller, and what a model says it can do.

Planning never tells models apart by their state size: it asks what the model can do. A model declares
- `holonomic`: it can move in any direction at once (no heading to turn first): the point mass;
- `turns_in_place`: it can change heading without travelling; a model that cannot (a tractor-trailer) needs
  room to turn round an obstacle's end, and manoeuvres (back and forth) out of tight corners;
- `reverses`: it can drive backwards;
- `trailer`: it pulls a trailer whose hitch angle must not fold.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from numpy.typing import NDArray

__all__ = ['Controller', 'RobotModel']

FloatArray = NDArray[np.float64]


class RobotModel(Protocol):
    """A robot's kinematics: its state, how a command moves it, and what it can do."""

    @property
    def state_size(self) -> int: ...

    @property
    def holonomic(self) -> bool: ...

    @property
    def turns_in_place(self) -> bool: ...

    @property
    def reverses(self) -> bool: ...

    @property
    def trailer(self) -> bool: ...

    def integrate(self, state: FloatArray, command: FloatArray, dt: float) -> FloatArray: ...

    def velocity(self, state: FloatArray, command: FloatArray) -> FloatArray: ...


class Controller(Protocol):
    """A kinematic controller: the command that drives a robot from its state toward a target point."""

    def reset(self, state: FloatArray, target: FloatArray) -> None: ...

    def command(self, state: FloatArray, target: FloatArray, dt: float) -> FloatArray: ...
