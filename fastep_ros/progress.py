"""What a navigation goal's feedback measures, and when a goal under way has stalled for good.

`Way`: the way the robot follows to the pose it drives to, frozen by a planning pass (PlannerNode.plan_pass: one
value, replaced whole, handed over with the pass's PassResult, as the plan is): FAStep-Route's route from the vertex
it drives to (the farthest in sight) through the later ones to the goal, or, without a route (the other
algorithms), the goal alone. Feedback's distance_remaining is `remaining(position)`: the straight run to that vertex,
then the route's length from it (Route.rest). It is not measured through the controller's aim point, which
FAStep-Route puts `lead` (max_speed / gain, 10 m) beyond its route vertex to keep full speed: summing the legs
through that point made distance_remaining jump 5 -> 21 m on a 5.4 m drive (issue "Nav2's own client").

`eta`: the time the distance left takes at the speed the robot can hold (max_speed as a speed limit caps it), with
the time a stop at that speed takes at max_acceleration beyond the distance itself (the last metres are slower).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ['SAME_GOAL', 'Way', 'eta']

SAME_GOAL = 1e-6   # m: a way frozen for a goal this near the pose driven to is that pose's (else: the straight run)


@dataclass(frozen=True)
class Way:
    """The way ahead as a pass left it: the goal it was planned to, and the route vertices still to drive to (the
    one driven to first, the goal last; none: the straight run to the goal) with the route length from each."""

    goal: tuple[float, float]
    vertices: NDArray[np.float64]   # (k, 2), copied: the route's own arrays are the planning side's
    rest: NDArray[np.float64]       # (k,) route length from each vertex to the goal

    @classmethod
    def of(cls, navigator: Any) -> Way | None:
        """The navigator's way now (on the side that owns it: a pass, or the executor in lock step); None without
        a goal."""
        goal = getattr(navigator, 'goal', None)
        if goal is None:
            return None
        route = getattr(navigator, 'route', None)   # FAStep-Route's (shortest_path/route.py); None: the others
        g = (float(goal[0]), float(goal[1]))
        if route is None or not len(route.stacked):
            return cls(g, np.zeros((0, 2)), np.zeros(0))
        last = route.stacked[-1]
        if math.hypot(float(last[0]) - g[0], float(last[1]) - g[1]) > SAME_GOAL:
            return cls(g, np.zeros((0, 2)), np.zeros(0))   # a route of another goal (a pass before set_goal's)
        index = min(int(route.index), len(route.stacked) - 1)
        return cls(g, route.stacked[index:].copy(), route.rest[index:].copy())

    def leads_to(self, point: tuple[float, float]) -> bool:
        return math.hypot(self.goal[0] - point[0], self.goal[1] - point[1]) <= SAME_GOAL

    def remaining(self, position: tuple[float, float]) -> float:
        """Length of the way left from `position`: to the vertex driven to, then along the route; the straight
        run to the goal without one."""
        if not len(self.vertices):
            return math.hypot(self.goal[0] - position[0], self.goal[1] - position[1])
        first = self.vertices[0]
        return math.hypot(float(first[0]) - position[0], float(first[1]) - position[1]) + float(self.rest[0])


def eta(distance: float, speed: float, deceleration: float) -> float:
    """Seconds `distance` takes at `speed` (the speed the robot can hold), a stop at `deceleration` included."""
    if speed <= 0.0:
        return 0.0
    if deceleration <= 0.0:
        return distance / speed
    stop = 0.5 * speed * speed / deceleration   # the distance a stop from `speed` takes
    if distance >= stop:
        return distance / speed + 0.5 * speed / deceleration   # the stop's metres take twice as long as at speed
    return math.sqrt(2.0 * distance / deceleration)
