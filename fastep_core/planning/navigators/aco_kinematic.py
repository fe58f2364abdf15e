"""ACO-Kinematic, the baseline FAStep-Kinematic is measured against (PeerJ Comput. Sci. 8:e905, 2022).

Continuous ACO (ACO_R, Socha & Dorigo 2008) plans every step, whether anything is in the way or not, with the
same fitness (eq. 10), clearance rule and step radius as FAStep-Kinematic; the robot drives straight to the
goal only for the last step, once the goal is within `step_radius` and nothing lies on the run to it. The
loop, the guard and the recoveries are the shared Navigator's (planning/navigator.py).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from fastep_core.planning.navigator import FloatArray, Mode, Navigator
from fastep_core.planning.others import OtherRobot

__all__ = ['ACOKinematic']


class ACOKinematic(Navigator):
    """The baseline: continuous ACO plans every step; straight to the goal only for the last one."""

    method = 'aco'
    step_method = 'aco'

    def choose_target(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        assert self.goal is not None
        if self.keep_waypoint(position, others):
            return self.waypoint
        if self.waypoint is None and self._target is not None and np.array_equal(self._target, self.goal) \
                and not self.blocked(position, self.goal, others):
            return self.goal
        reach = float(np.hypot(*(self.goal - position))) <= self.params.step_radius
        if reach and not self.blocked(position, self.goal, others, sensing_range=math.inf):
            self.waypoint, self.cost, self.mode, self.reason = None, 0.0, Mode.KINEMATIC, 'last step'
            return self.goal
        return self.plan_next_step(position, others)
