"""The way out of a trap: the exact shortest path, followed by a pure-pursuit carrot.

Why: greedy steps (far from obstacles, closer to the goal) settle in local minima such as the inside of a
U-shaped wall, and no step radius or weight removes every such minimum. The exact planner
(planning/shortest_path/optimal.py) knows the way out; the navigator drives it with its own kinematic controller.

How the path is driven: the target is the farthest path vertex within `step_radius` that the robot can see (a
straight run keeping the path's clearance, a hair less), pushed out along the same bearing to `step_radius`
when that run is free too. The kinematic controllers slow down in proportion to the distance to their target,
so aiming at a vertex a few centimetres ahead on a tight arc would make the robot crawl. When not even the next
vertex is in sight (after a backup, or a tractor-trailer's swing), the caller plans the path again from where
the robot is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Protocol

import numpy as np
from numpy.typing import NDArray

from fastep_core.planning.shortest_path.optimal import OptimalPath
from fastep_core.world import World

__all__ = ['ADOPT_REACH', 'ESCAPING', 'MAX_VERTICES', 'REPLAN_AFTER', 'EscapePath', 'TrapEscape', 'densify']

FloatArray = NDArray[np.float64]
ESCAPING = 'escaping a trap along the exact shortest path'   # the status reason while escaping
REPLAN_AFTER = 0.5   # seconds: a path with no vertex in sight is planned again at most this often
ADOPT_REACH = 20.0   # metres of path ahead checked against a world known anew (TrapEscape.adopt)


class EscapeParams(Protocol):
    """The planner parameters an escape reads (PlannerParams has them)."""

    @property
    def clearance_margin(self) -> float: ...

    @property
    def step_radius(self) -> float: ...

    @property
    def waypoint_tolerance(self) -> float: ...

    @property
    def progress_distance(self) -> float: ...


MAX_VERTICES = 20_000
"""Most vertices a densified path gets: spacing 0.5 m up to 10 km of path, coarser beyond (it was unbounded:
a far goal, or coordinates near 1e299, ended in MemoryError)."""


def densify(points: FloatArray, spacing: float = 0.5) -> list[FloatArray]:
    """The polyline with extra vertices on long edges, so a pursuit carrot never lags far behind the lookahead.

    One array per vertex: the navigator tells a new target by its identity. At most MAX_VERTICES extra
    vertices: on a path longer than MAX_VERTICES * spacing they are spread evenly over its length instead.
    """
    legs = [math.hypot(*(b - a)) for a, b in zip(points[:-1], points[1:])]
    total = math.fsum(legs)
    if total > MAX_VERTICES * spacing:
        spacing = total / MAX_VERTICES          # inf for an overflowing length: no extra vertex at all
    out = [points[0]]
    for a, b, leg in zip(points[:-1], points[1:], legs):
        n = max(1, int(math.ceil(leg / spacing))) if math.isfinite(leg / spacing) else 1
        out.extend(a + (b - a) * (k / n) for k in range(1, n + 1))
    return out


@dataclass
class EscapePath:
    """An exact path being followed: its vertices after the start, what they keep, and how far along we are.

    What `target` measures each tick (the clearance of the runs from the robot to the vertices ahead, and to
    the carrot; the robot's own clearance) is kept, with the position it was measured from, and reused while
    it still decides the same: a run's clearance changes by at most the distance its ends moved, a point's by
    at most the distance it moved. So a run that kept `within` with more room than the robot has moved since
    still keeps it, one that missed it by more still misses it, and only the runs in between are measured
    again. Every decision is the one measuring all of them gives (with a rounding margin, 1e-6 m relative to
    the coordinates' size, far beyond the floats' own error).
    """

    vertices: list[FloatArray]   # after the start, the goal last
    rest: FloatArray             # path length from each vertex to the goal
    keep: float                  # the clearance the path keeps ...
    world: World                 # ... from the obstacles of this world (parked robots included)
    index: int = 0               # the vertex aimed at
    stacked: FloatArray = field(init=False, repr=False)   # the vertices as one (n, 2) array, made once
    # The clearance of the run to each vertex (nan: not measured yet) and where the robot was then.
    fan: FloatArray = field(init=False, repr=False)
    fan_from: FloatArray = field(init=False, repr=False)
    # The last carrot's run (start x, y, end x, y, clearance) and the robot's clearance (x, y, clearance).
    carrot_run: tuple[float, float, float, float, float] | None = field(init=False, repr=False, default=None)
    room: tuple[float, float, float] | None = field(init=False, repr=False, default=None)

    def __post_init__(self) -> None:
        self.stacked = np.array(self.vertices, dtype=float).reshape(-1, 2)
        self.fan = np.full(len(self.stacked), np.nan)
        self.fan_from = np.zeros((2, len(self.stacked)))

    @classmethod
    def from_path(cls, path: OptimalPath, world: World) -> EscapePath:
        points = densify(path.points)
        legs = np.hypot(*np.diff(np.array(points), axis=0).T)
        rest = np.concatenate([np.cumsum(legs[::-1])[::-1][1:], [0.0]])
        return cls(points[1:], rest, path.clearance, world)

    def measure_in(self, world: World) -> None:
        """Measure sight against `world` from now on (the robot knows it now); nothing measured before is kept."""
        self.world = world
        self.fan[:] = np.nan
        self.carrot_run = self.room = None

    def remaining(self, position: FloatArray) -> float:
        """Path length left from position (via the vertex aimed at)."""
        return math.hypot(*(self.vertices[self.index] - position)) + float(self.rest[self.index])

    def target(self, position: FloatArray, radius: float, margin: float, step_radius: float,
               waypoint_tolerance: float, clearance: float, fresh: bool = False) -> FloatArray | None:
        """The pursuit target, or None when no vertex ahead is in sight (unless the path is `fresh`, planned
        from this position, so its first vertex is reachable by construction).

        radius, margin: the robot's; clearance: radius + margin, kept from the border by a pushed-out carrot.
        """
        route = self.vertices
        gaps = np.hypot(*(self.stacked[self.index:] - position).T)
        beyond = gaps > step_radius
        reach = max(1, int(np.argmax(beyond)) if beyond.any() else len(gaps))
        obstacles = self.world.obstacles
        # A path vertex sits exactly at the path's clearance, so "visible" allows a little less: half the margin,
        # what the path keeps (in a narrow gap), or what the robot has now, whichever is smallest (the guard
        # still keeps the radius).
        within = min(radius + 0.5 * margin, self.keep - 1e-3)
        x, y = float(position[0]), float(position[1])
        slack = 1e-6 * (1.0 + max(abs(x), abs(y), obstacles.scale))
        if len(obstacles):
            within = self._within(x, y, within, slack)
            seen = self._seen(position, self.index, self.index + reach, within, slack)
        else:
            seen = np.ones(reach, dtype=bool)
        # Round a wall's end the path is an arc at the clearance it keeps, and a robot that cut a chord of it (by
        # up to what `within` allows) sees the next vertex only along a chord that dips a little lower still.
        # The vertex aimed at, and the next one once the robot is on it, count as in sight down to a quarter
        # margin less (not below radius + a quarter margin, the slack the guard leaves): else the path is
        # planned again from there, keeping only what the robot has, and the robot crawls round the arc
        # planning a path every REPLAN_AFTER (docs/clutter.md, "Trap escapes round a wall's end").
        lower = min(within, max(within - 0.25 * margin, radius + 0.25 * margin))
        if len(obstacles) and not seen[0] and lower < within:
            seen[0] = self._seen(position, self.index, self.index + 1, lower, slack)[0]
        if not seen.any():
            if not fresh:
                return None
            seen[0] = True
        last = int(np.flatnonzero(seen)[-1])
        if last == 0 and gaps[0] <= waypoint_tolerance and len(gaps) > 1 and not fresh:
            if not (len(obstacles) and lower < within and
                    self._seen(position, self.index + 1, self.index + 2, lower, slack)[0]):
                return None   # on the aimed vertex and not even the next one in sight
            last = 1
        self.index += last
        aim = route[self.index]
        if self.index == len(route) - 1:
            return aim   # the goal itself
        gap = math.hypot(*(aim - position))
        if gap < 1e-9 or gap >= step_radius:
            return aim
        carrot = position + (aim - position) * (step_radius / gap)
        if float(self.world.wall_distance(carrot)) < clearance or \
                (len(obstacles) and self._carrot_clearance(position, carrot, within, slack) < within):
            return aim
        return carrot   # a new array each tick: the controller is reset, as pure pursuit needs

    def _within(self, x: float, y: float, within: float, slack: float) -> float:
        """min(within, the robot's clearance - 1e-6), measuring the clearance only when it may be the smaller."""
        room = self.room
        if room is not None and room[2] - math.hypot(x - room[0], y - room[1]) - slack - 1e-6 > within:
            return within
        here = float(self.world.obstacles.clearance(np.array([x, y])))
        self.room = (x, y, here)
        return min(within, here - 1e-6)

    def _seen(self, position: FloatArray, first: int, stop: int, within: float, slack: float) -> NDArray[np.bool_]:
        """fan_clearance(position, vertices first..stop-1) >= within, measuring only the runs still in doubt."""
        fan, origin = self.fan[first:stop], self.fan_from[:, first:stop]
        moved = np.hypot(position[0] - origin[0], position[1] - origin[1])
        moved += slack
        seen: NDArray[np.bool_] = fan - moved >= within
        doubt = ~(seen | (fan + moved < within))      # nan (never measured) is in doubt
        if doubt.any():
            at = np.flatnonzero(doubt)
            measured = self.world.obstacles.fan_clearance(position, self.stacked[first + at])
            fan[at] = measured
            origin[0, at], origin[1, at] = position[0], position[1]
            seen[at] = measured >= within
        return seen

    def _carrot_clearance(self, position: FloatArray, carrot: FloatArray, within: float, slack: float) -> float:
        """fan_clearance(position, [carrot]) where it decides `< within`; the last carrot's when that proves it."""
        x, y, cx, cy = float(position[0]), float(position[1]), float(carrot[0]), float(carrot[1])
        last = self.carrot_run
        if last is not None:
            moved = max(math.hypot(x - last[0], y - last[1]), math.hypot(cx - last[2], cy - last[3])) + slack
            if last[4] - moved >= within or last[4] + moved < within:
                return last[4]
        clear = float(self.world.obstacles.fan_clearance(position, carrot[None])[0])
        self.carrot_run = (x, y, cx, cy, clear)
        return clear


class TrapEscape:
    """A trap escape in progress: the path followed, when it was planned, and when the robot is out.

    The robot hands back to its algorithm once it is `progress_distance` closer to the goal than it ever was
    in the trap (the leave rule of the Bug algorithms), so each escape ends strictly closer to the goal and
    escapes cannot cycle. The path is planned again when no vertex ahead is in sight, at most every
    REPLAN_AFTER seconds, and when what the robot knows of the world has changed so that the rest of the path
    comes too near an obstacle (`adopt`). Progress along an escape is a shorter way left to go (path length),
    not a smaller distance to the goal.
    """

    def __init__(self) -> None:
        self.path: EscapePath | None = None   # the way out, while escaping
        self.planned_at = -math.inf           # when it was last planned
        self.exit = 0.0                       # hand back to the algorithm once this close to the goal
        self.best = math.inf                  # the shortest way left so far
        self.known: World | None = None       # the world the robot knew when the path was planned

    @property
    def active(self) -> bool:
        return self.path is not None

    def start(self, path: OptimalPath, world: World, t: float, exit_distance: float,
              known: World | None = None) -> None:
        """Escape along `path` (planned in `world`, parked robots included, when the robot knew `known`)."""
        self.replan(path, world, t, known)
        self.exit, self.best = exit_distance, math.inf

    def replan(self, path: OptimalPath, world: World, t: float, known: World | None = None) -> None:
        """Follow a new path (planned in `world`, parked robots included, when the robot knew `known`)."""
        self.path, self.planned_at, self.known = EscapePath.from_path(path, world), t, known

    def stop(self) -> None:
        self.path = None

    def left(self, distance: float) -> bool:
        """Is the robot out of the trap (and the escape over) at `distance` from the goal?"""
        if distance <= self.exit:
            self.path = None
            return True
        return False

    def adopt(self, known: World, world: World, keep: float) -> bool:
        """The robot knows `known` now (`world`: the same with the parked robots, as a path is planned in): go on
        along the path, measured against `world` from now on, when the rest of it keeps `keep` there (True);
        False when it does not, and the path must be planned again.

        Why not plan again at every change: a sensing robot's world changes with every correction of an obstacle
        it had misplaced, and a path planned from where the robot stands keeps only the clearance it has there,
        all the way (exact_path): replanned from every sag, an escape hugged walls ever closer.
        """
        path = self.path
        assert path is not None
        # The next ADOPT_REACH metres of it (a path across a big map has thousands of vertices, and the world of a
        # sensing robot changes often); farther on, a sensed obstacle is met as one out of sight, and planned round.
        stop = int(np.searchsorted(-path.rest, -(path.rest[path.index] - ADOPT_REACH), side='right'))
        ahead = path.stacked[path.index:max(stop, path.index + 2)]
        if len(world.obstacles) and len(ahead) > 1 and \
                float(world.obstacles.path_clearance(ahead[:-1], ahead[1:]).min()) < keep:
            return False
        path.measure_in(world)
        self.known = known
        return True

    def next_target(self, position: FloatArray, t: float, plan: Callable[[], tuple[OptimalPath, World] | None],
                    radius: float, params: EscapeParams, replan: bool = False,
                    known: World | None = None) -> tuple[FloatArray | None, bool]:
        """The pursuit target and whether the way left got `progress_distance` shorter; (None, False) when the
        path had to be planned again (`replan` asks for that) and `plan()` found none. `known`: the world the
        robot knows now, recorded with a path planned here."""
        if not replan:
            target, progressed = self._pursue(position, radius, params, fresh=t - self.planned_at < REPLAN_AFTER)
            if target is not None:
                return target, progressed
        found = plan()
        if found is None:
            return None, False
        self.replan(*found, t, known)
        return self._pursue(position, radius, params, fresh=True)

    def _pursue(self, position: FloatArray, radius: float, params: EscapeParams,
                fresh: bool) -> tuple[FloatArray | None, bool]:
        assert self.path is not None
        p = params
        target = self.path.target(position, radius, p.clearance_margin, p.step_radius, p.waypoint_tolerance,
                                  radius + p.clearance_margin, fresh)
        if target is None:
            return None, False
        rest = self.path.remaining(position)
        if rest < self.best - p.progress_distance:
            self.best = rest
            return target, True
        return target, False
