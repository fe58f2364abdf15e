"""A robot model driven by its own controller toward a fixed target, without a world: the kinematics tests."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

__all__ = ['drive']


def drive(model: Any, controller: Any, state: ArrayLike, target: ArrayLike, dt: float = 0.05,
          steps: int = 4000) -> np.ndarray:
    """The states (steps + 1 rows, the start first) of `model` commanded by `controller` toward `target`."""
    goal = np.asarray(target, dtype=float)
    states = [np.asarray(state, dtype=float)]
    controller.reset(states[0], goal)
    applied = getattr(controller, 'applied', None)   # a controller with acceleration limits (diff_drive)
    for _ in range(steps):
        command = controller.command(states[-1], goal, dt)
        if applied is not None:
            applied(command)
        states.append(model.integrate(states[-1], command, dt))
    return np.array(states)
