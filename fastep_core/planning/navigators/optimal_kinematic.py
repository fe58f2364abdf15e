"""Optimal-Kinematic: the exact shortest path, planned once, driven by the same kinematic controller.

Why: to tell how much of FAStep-Kinematic's extra path length comes from its step-by-step swarm and how much
from driving a kinematic robot through waypoints, the reference must be driven the same way. This navigator
plans `planning.optimal.shortest_path` (clearance = radius + clearance_margin) once per goal, on its first tick
(so the planning time counts in the run's compute time), and steers to the polyline's vertices in turn. Arcs
become vertices at most `ARC_SPACING` apart on a circumscribed polygon, so every chord keeps the clearance.

It knows static obstacles only: other robots are left to the guard and the hold breaker, whose step is planned
by the FAStep swarm before the exact path is planned again, so it is a reference for single-robot runs. Where
the only way through is narrower than the clearance it keeps the radius alone; a robot already closer plans with
the clearance it has, never less than its radius; a goal with no path fails with 'no valid path'.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from fastep_core.planning.navigator import Mode, Navigator
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.shortest_path.exact_path import PATH_SPACING
from fastep_core.planning.shortest_path.optimal import OptimalPath

__all__ = ['OptimalKinematic', 'ARC_SPACING']

ARC_SPACING = PATH_SPACING
"""Largest distance (m) between consecutive polyline vertices along an arc (the navigator's exact_path)."""


class OptimalKinematic(Navigator):
    """Follow the exact shortest clearance-keeping path, vertex by vertex, with the kinematic controller."""

    method = 'optimal'
    escapes_traps = False                    # it follows the exact path already
    path: OptimalPath | None = None          # the exact path of the current goal, once planned
    _route: np.ndarray | None = None         # its polyline vertices after the start
    _index = 0                               # the vertex driven to now
    _detour = False                          # following a swarm step around another robot

    def set_goal(self, goal: Sequence[float], t: float = 0.0, heading: float | None = None) -> None:
        super().set_goal(goal, t, heading)
        self.path, self._route, self._index, self._detour = None, None, 0, False

    def _plan(self, position: np.ndarray) -> bool:
        assert self.goal is not None
        self.activations += 1
        path = self.reference if self.reference is not None and np.array_equal(self.reference.points[0], position) \
            else self.exact_path(position)
        if path is None:
            self.fail_no_path(position)
            return False
        self.path = path
        self._route = path.points[1:] if len(path.points) > 1 else path.points
        self._index = 0
        self.plan = [p.copy() for p in self._route[:-1]]
        return True

    def plan_next_step(self, position: np.ndarray, others: Sequence[OtherRobot]) -> np.ndarray | None:
        """A swarm step around another robot (the hold breaker); the exact path is replanned after it."""
        step = super().plan_next_step(position, others)   # with the FAStep swarm (step_method)
        if step is not None:
            self._detour, self._route = True, None
        return step

    def choose_target(self, position: np.ndarray, others: Sequence[OtherRobot]) -> np.ndarray | None:
        assert self.goal is not None
        if self._detour:
            if self.keep_waypoint(position, others):
                return self.waypoint
            self._detour = False
        if self._route is None and not self._plan(position):
            return None
        assert self._route is not None
        last = len(self._route) - 1
        while self._index < last and \
                np.hypot(*(self._route[self._index] - position)) <= self.params.waypoint_tolerance:
            self._index += 1
        if self._index >= last:
            self.waypoint, self.mode, self.reason = None, Mode.KINEMATIC, 'last leg of the optimal path'
            return self.goal
        self.waypoint = self._route[self._index]
        self.mode, self.reason = Mode.AVOIDING, 'following the optimal path'
        return self.waypoint
