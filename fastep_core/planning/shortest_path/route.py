"""A robot's route (the exact shortest path it follows) and the speed it may drive along it.

`Route` keeps the path's vertices with the length of route left from each and answers which vertex ahead is in
sight (with a proof of how far the robot may move while the answer holds), and whether a world known anew still
leaves the route its clearance (`adopt`). `RouteSpeed` is the speed law along it: as fast as the base, the curvature
ahead and the clearance allow, slowing for the goal, turns and tight gaps (Nav2's Regulated Pure Pursuit is the
anchor). FAStep-Route (fastep_route.py) plans routes and drives them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import Circle, Obstacle, Obstacles
from fastep_core.planning.limits import Limits
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.recovery.escape import ADOPT_REACH  # as far ahead as an escape path is checked
from fastep_core.planning.shortest_path.optimal import OptimalPath
from fastep_core.world import World

__all__ = ['COVERED', 'REMOVED_REACH', 'SIGHT', 'SIGHT_VERTICES', 'Route', 'RouteSpeed', 'SightProof', 'covered']

FloatArray = NDArray[np.float64]
SIGHT = 30.0            # m of route ahead whose vertices are tested for sight
SIGHT_VERTICES = 256    # vertices tested for sight at most
REMOVED_REACH = 1.0     # m beyond its clearance: an obstacle gone from this near the route may have bent it
COVERED = 0.05          # m: an obstacle whose points other obstacles come this near is still there (covered)
SightProof = tuple[int, float, float, float, float, float, int | None]
"""An answer of Route.in_sight proven: the index it was asked at, the position (x, y), radius and margin, how far
the robot may move while it holds, and the answer."""


def covered(item: Obstacle, world: World) -> bool:
    """Is the obstacle still there in `world`, as part of others (a wall piece a longer one continues, a circle a
    new fit replaced): its ends and middle (a circle: its centre and four points of its rim) within COVERED of them?"""
    if not len(world.obstacles):
        return False
    if isinstance(item, Circle):
        cx, cy, r = item.center[0], item.center[1], item.radius
        points = np.array([[cx, cy], [cx + r, cy], [cx - r, cy], [cx, cy + r], [cx, cy - r]])
    else:
        points = np.array([item.start, item.end,
                           [(item.start[0] + item.end[0]) / 2, (item.start[1] + item.end[1]) / 2]])
    return bool((world.obstacles.clearance(points) <= COVERED).all())


@dataclass
class Route:
    """The route being followed: its vertices after the start (the goal last), and what it was planned for."""

    vertices: list[FloatArray]   # one array per vertex: the navigator tells a new target by its identity
    keep: float                  # the clearance the route keeps ...
    world: World                 # ... from the obstacles of this world (robots standing still included)
    base: World                  # the navigator's world when the route was planned
    parked: FloatArray           # (k, 2) centres of the robots the route was planned round
    index: int = 0               # the vertex in sight farthest along the route, last time it was looked for
    stacked: FloatArray = field(init=False, repr=False)   # the vertices as one (n, 2) array
    rest: FloatArray = field(init=False, repr=False)      # route length from each vertex to the goal
    ahead: NDArray[np.intp] = field(init=False, repr=False)   # vertices tested for sight from each index
    # What in_sight measured, kept while it is proven (see in_sight): its last answer that left `index` where it
    # was, and the robot's clearance with where it was measured (x, y, clearance).
    sight_proof: SightProof | None = field(default=None, init=False, repr=False)
    clearance_at: tuple[float, float, float] | None = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        self.stacked = np.array(self.vertices, dtype=float).reshape(-1, 2)
        legs = np.hypot(*np.diff(self.stacked, axis=0).T)
        self.rest = np.concatenate([np.cumsum(legs[::-1])[::-1], [0.0]])
        # The vertices within SIGHT metres of route from each one (SIGHT_VERTICES at most; 2 however far): rest
        # never grows along the route (sums of legs), so one search over all of it counts those of each suffix.
        within_sight = np.searchsorted(-self.rest, -(self.rest - SIGHT), side='right') - np.arange(len(self.rest))
        self.ahead = np.maximum(2, np.minimum(SIGHT_VERTICES, within_sight))

    @classmethod
    def from_path(cls, path: OptimalPath, world: World, base: World, parked: FloatArray) -> Route:
        points = path.points[1:] if len(path.points) > 1 else path.points
        return cls([p.copy() for p in points], path.clearance, world, base, parked)

    def adopt(self, known: World, position: FloatArray, margin: float) -> bool:
        """The navigator knows `known` now, the route having been planned in `base`: go on along it, measured
        against `known` from now on (True), when the next ADOPT_REACH metres of it (from `position`) keep its
        clearance there (the leg to the vertex in sight half the margin less, as in_sight lets it) and no obstacle
        it was planned round has gone from within REMOVED_REACH of it (the way may be shorter now); else False, and
        it is planned again. Only a route planned round no robot standing still (its world is the base then).

        Why not plan again at every change: a robot perceiving clutter knows a new obstacle or a longer wall
        piece most ticks, and an exact path each time was most of its planning (dense_clutter_laser: a replan
        every other tick)."""
        if len(self.parked) or self.world is not self.base:
            return False
        legs = self.stacked[self.index:]
        stop = int(np.searchsorted(-self.rest[self.index:], -(self.rest[self.index] - ADOPT_REACH), side='right'))
        ahead = np.vstack([np.asarray(position, dtype=float)[None, :2], legs[:max(stop, 1) + 1]])
        a, b = ahead[:-1], ahead[1:]
        keep = np.full(len(a), self.keep - 1e-6)
        keep[0] -= 0.5 * margin
        if len(known.obstacles) and (known.obstacles.path_clearance(a, b) < keep).any():
            return False
        present = {id(item) for item in known.obstacle_list}
        removed = [item for item in self.base.obstacle_list if id(item) not in present and not covered(item, known)]
        if removed and float(Obstacles(removed).path_clearance(a, b).min()) < self.keep + REMOVED_REACH:
            return False
        self.world = self.base = known
        self.sight_proof = self.clearance_at = None
        return True

    def remaining(self, position: FloatArray) -> float:
        """Route length left from position (via the vertex last in sight)."""
        vertex = self.vertices[self.index]   # in floats: called every tick, numpy's per-call cost was most of it
        return math.hypot(float(vertex[0]) - float(position[0]), float(vertex[1]) - float(position[1])) + \
            float(self.rest[self.index])

    def in_sight(self, position: FloatArray, radius: float, margin: float) -> int | None:
        """The index of the farthest route vertex in sight from position (and `index` moves there); None when no
        vertex ahead is in sight.

        In sight: the straight run keeps the route's clearance less half the margin (a vertex lies exactly at
        the route's clearance; a route through a narrow gap, keeping less than radius + margin, a hair less).
        So a route that keeps turn room for a robot that cannot turn in place is not cut short round a bend. A
        robot already nearer than that (it cut a corner by up to that half margin) may see along runs that
        keep a quarter margin less, or what it has now if that is less: else the next leg, passing a few
        millimetres nearer than the robot is, would be out of sight and the route planned at every bend.
        Of the vertices ahead (within SIGHT metres of route, SIGHT_VERTICES at most) the first one in sight and
        the run of vertices in sight after it count; the last of that run is the farthest. The first of them is
        the one aimed at so far, which stays in sight down to a quarter margin less (hysteresis).

        The answer is what measuring every run gives, but measurements are skipped while they are proven: a
        point's distance to an obstacle surface, and a run's (its far end fixed), change by at most the distance
        the robot moved. So the robot's clearance is measured only when it may have come below the usual
        threshold, and an answer that left `index` where it was is kept while the robot has moved less than its
        room: the clearance stays on the same side of the usual threshold (and `within` moves by less than the
        robot did), and no run can cross its threshold while the robot moves less than half its distance from
        it. The rooms are shortened by a rounding margin far beyond the floats' own error (1e-6 m, relative to
        the coordinates' size), as in detection.RunDetector.obstacles_on_run.
        """
        x, y = float(position[0]), float(position[1])
        proof = self.sight_proof
        if proof is not None and proof[0] == self.index and proof[3] == radius and proof[4] == margin and \
                math.hypot(x - proof[1], y - proof[2]) < proof[5]:
            return proof[6]
        self.sight_proof = None
        candidates = self.stacked[self.index:self.index + int(self.ahead[self.index])]   # the next one, however far
        obstacles = self.world.obstacles
        within = max(self.keep - 0.5 * margin, min(radius + 0.5 * margin, self.keep - 1e-3))
        if not len(obstacles):
            seen = np.ones(len(candidates), dtype=bool)
        else:
            slack = 1e-6 * (1.0 + max(abs(x), abs(y), float(np.abs(candidates).max()), obstacles.scale))
            usual = within
            # The branch below is decided by the robot's clearance; `margin_of_branch` is how far it is (at
            # least) from the usual threshold, which is what the answer's room starts from.
            known = self.clearance_at
            least = -math.inf if known is None else known[2] - math.hypot(x - known[0], y - known[1])
            if least - slack > usual:
                margin_of_branch = least - usual
            else:
                here = float(obstacles.clearance(position))
                self.clearance_at = (x, y, here)
                margin_of_branch = abs(here - usual)
                if here < within:
                    within = min(within - 0.25 * margin, here) - 1e-6
            runs = obstacles.fan_clearance(position, candidates)
            seen = runs >= within
            # The vertex aimed at so far (the first candidate) stays in sight a quarter margin longer: the robot
            # drives the run to it, which keeps what it kept, give or take a rounding error or a trailer's curve.
            first_within = within - 0.25 * margin
            seen[0] = runs[0] >= first_within
        if not seen.any():
            answer, last = None, 0
        else:
            first = int(np.argmax(seen))
            hidden = np.flatnonzero(~seen[first:])
            last = first + (int(hidden[0]) - 1 if len(hidden) else len(seen) - first - 1)
            self.index += last
            answer = self.index
        if last == 0 and len(obstacles):
            gaps = np.abs(runs - within)
            gaps[0] = abs(float(runs[0]) - first_within)
            room = min(margin_of_branch, 0.5 * float(gaps.min())) - slack
            if room > 0.0 and math.isfinite(room):
                self.sight_proof = (self.index, x, y, radius, margin, room, answer)
        return answer

    def passing(self, position: FloatArray, tolerance: float) -> None:
        """Aim past the vertices within `tolerance` of position (a vertex counts as passed, as any waypoint):
        the next vertex is in sight from there by construction, and aiming beyond a vertex the robot stands on
        would turn round with every tick."""
        last = len(self.vertices) - 1
        while self.index < last and math.hypot(*(self.stacked[self.index] - position)) <= tolerance:
            self.index += 1


@dataclass(frozen=True)
class RouteSpeed:
    """FAStep-Route's speed law on one route (params.regulated_speed; the module's "Speed"), frozen when made."""

    vertices: FloatArray                  # (n, 2) the route's vertices
    rest: FloatArray                      # route length from each vertex to the goal
    index: int                            # the vertex aimed at ...
    vertex: FloatArray                    # ... itself
    aim: FloatArray | None                # where the controller is aimed for it (beyond it)
    goal: FloatArray
    at_goal: bool                         # the vertex aimed at is the goal
    radius: float
    params: PlannerParams
    world: World
    holonomic: bool
    clearance_at: tuple[float, float, float] | None   # a clearance known at a point (x, y, clearance)
    braking: float                        # what stops are planned at: max_acceleration or what the base showed
    limits: Limits                        # max_speed and max_acceleration (the navigator's)

    def under(self, limits: Limits, braking: float) -> RouteSpeed:
        """The same law within other limits (changed at runtime after it was frozen), stops planned at `braking`
        (what the base has shown, within the new max_acceleration)."""
        return replace(self, limits=limits, braking=braking)

    def regulate(self, state: FloatArray, command: FloatArray, dt: float,
                 last: FloatArray | None = None) -> FloatArray:
        """The command no faster than `allowed`, scaled whole (a steered robot keeps its curvature, a tractor its
        steering angle within its lock), and never braking harder than max_acceleration from `last`, the command
        the robot got last tick (where a new bend or a tight gap asks for less at once)."""
        allowed = self.allowed(state[:2], dt)
        speed = math.hypot(float(command[0]), float(command[1])) if self.holonomic else abs(float(command[0]))
        acceleration = self.limits.max_acceleration
        if last is not None and acceleration > 0.0:
            before = math.hypot(float(last[0]), float(last[1])) if self.holonomic else abs(float(last[0]))
            allowed = max(allowed, min(speed, before - acceleration * dt))
        return command if speed <= allowed else command * (allowed / speed)

    def allowed(self, position: FloatArray, dt: float) -> float:
        """The speed the way allows at position: max_speed, braking at `braking` (max_acceleration, or less where the
        base has shown less: planning/safety/base_response.py) to stop at the goal and to take the bend at the vertex
        aimed at, and less in a gap tighter than radius + clearance_margin; never below min_approach_speed (or what
        reaches the goal in a tick) short of the goal, nothing past it."""
        p, vertex, goal = self.params, self.vertex, self.goal
        x, y = float(position[0]), float(position[1])
        top = self.limits.max_speed if self.limits.max_speed > 0.0 else math.inf
        braking = self.braking if self.braking > 0.0 else math.inf
        ahead = (float(vertex[0]) - x, float(vertex[1]) - y)
        gap = math.hypot(*ahead)
        if self.at_goal:
            # Measured along the way driven (aimed beyond the goal): once past it, nothing is allowed (a stale
            # plan aimed beyond the goal must not carry the robot on).
            aim = self.aim if self.aim is not None else vertex
            way = (float(aim[0]) - x, float(aim[1]) - y)
            length = math.hypot(*way)
            left = ((float(goal[0]) - x) * way[0] + (float(goal[1]) - y) * way[1]) / length if length > 1e-9 else 0.0
        else:
            left = gap + float(self.rest[self.index])
        if left <= 0.0:
            return 0.0
        allowed = min(top, math.sqrt(2.0 * braking * left))
        if not self.at_goal and self.index + 1 < len(self.vertices) and gap > 1e-9:
            after = self.vertices[self.index + 1] - vertex
            length = math.hypot(float(after[0]), float(after[1]))
            bend = (ahead[0] * float(after[0]) + ahead[1] * float(after[1])) / (gap * length) if length > 1e-9 else 1.0
            corner = max(p.min_approach_speed, min(top, top * max(bend, 0.0)))
            allowed = min(allowed, math.sqrt(corner * corner + 2.0 * braking * gap))
        obstacles = self.world.obstacles
        if len(obstacles) and p.clearance_margin > 0.0:
            known = self.clearance_at
            least = -math.inf if known is None else known[2] - math.hypot(x - known[0], y - known[1])
            if least < self.radius + p.clearance_margin:
                room = float(obstacles.clearance(position)) - self.radius
                if room < p.clearance_margin:
                    allowed = min(allowed, max(p.min_approach_speed, top * max(room, 0.0) / p.clearance_margin))
        return max(allowed, min(p.min_approach_speed, left / dt))
