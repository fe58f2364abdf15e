"""The exact shortest path a robot can take to its goal, as the navigator asks for it.

planning/shortest_path/optimal.py computes the shortest path that keeps a given clearance. A navigator needs a little
more around it: which clearance to keep (the planner's radius + margin where there is room, less down to the
radius through a narrow gap, more where a robot that cannot turn in place needs room to turn), and which
other robots to plan round (those standing still). Used to refuse a goal with no path on the first tick, by
trap escapes (planning/recovery/escape.py) and by Optimal-Kinematic (planning/navigators/optimal_kinematic.py).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import Circle, Obstacles
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.shortest_path.optimal import OptimalPath, PathPiece, shortest_path
from fastep_core.world import World

if TYPE_CHECKING:   # scenario.py imports planning (params): only for the annotation
    from fastep_core.scenario import Scenario

__all__ = ['BACK_OUT', 'BLOCKED_RETRY', 'PARKED_SPEED', 'PATH_SPACING', 'TURN_ROOM', 'NoPathHold', 'backed_out',
           'blocked_reason', 'exact_path', 'in_the_way', 'no_path_reason', 'parked_world', 'robot_path', 'solvable']

FloatArray = NDArray[np.float64]
PATH_SPACING = 0.25   # metres between exact-path vertices along arcs (escape paths, the optimal reference)
TURN_ROOM = 1.0       # extra clearance (m) for a robot that cannot turn in place, where there is room for it
PARKED_SPEED = 0.05   # m/s: another robot slower than this is planned around like an obstacle
BACK_OUT = 0.05       # m inside its radius a robot may find itself and still back out (planning from scans)
BACK_OUT_SLACK = 0.01  # m beyond the radius the way out ends
BACK_OUT_DIRECTIONS = 16
BLOCKED_RETRY = 1.0   # s: a robot blocked in what it believes looks for a path again at least this often


def exact_path(world: World, position: FloatArray, goal: FloatArray, radius: float, params: PlannerParams, *,
               turn_room: bool = False, floor: float | None = None) -> OptimalPath | None:
    """The shortest path from position to goal keeping the most clearance it can, or None when there is none.

    It keeps the planner's clearance (radius + margin) where it can, and less (down to `floor`, by default the
    radius) when the one way through is narrower: a robot that fits through a gap has a path, even if its
    steps never go there. A start or goal already nearer an obstacle than the clearance lowers it to that
    distance. With `turn_room` the path first tries TURN_ROOM more.
    """
    clearance = radius + params.clearance_margin
    if len(world.obstacles):
        start = backed_out(world, position, radius)
        if start is not position:
            # A few millimetres inside the radius (a new scan put an obstacle nearer than believed): the path
            # starts with the way out, and keeps the radius from there.
            path = exact_path(world, start, goal, radius, params, turn_room=turn_room, floor=floor)
            return None if path is None else _from(position, path)
        ends = np.array([position, goal])
        clearance = min(clearance, float(world.obstacles.clearance(ends).min()) - 1e-9)
    path = None
    # Through a narrow gap the path keeps a quarter margin when it can (the guard stops at the radius
    # itself, so a path at exactly the radius would leave no slack for the controller).
    narrow = (min(clearance, radius + 0.25 * params.clearance_margin), min(clearance, radius))
    # A robot that cannot turn in place cannot wrap tightly round a wall's end (it circles there).
    wide = (clearance + TURN_ROOM,) if turn_room else ()
    floor = radius - 1e-9 if floor is None else floor
    for keep in dict.fromkeys((*wide, clearance, *narrow)):
        if keep >= floor and keep > 0.0:
            path = shortest_path(world, position, goal, keep, spacing=PATH_SPACING)
            if path is not None:
                break
    return path


def backed_out(world: World, position: FloatArray, radius: float) -> FloatArray:
    """`position` itself when it keeps the radius from every obstacle and the border (or lies deeper inside than
    BACK_OUT: that is no robot's way out); else the point, of BACK_OUT_DIRECTIONS around it at the nearest of a
    few distances up to BACK_OUT (+ slack), with the most room, once that keeps the radius and BACK_OUT_SLACK
    more (itself when none does)."""
    inside = radius - float(world.room(np.asarray(position, dtype=float)[None, :2])[0])
    if inside <= 0.0 or inside > BACK_OUT:
        return position
    angles = np.linspace(0.0, 2.0 * math.pi, BACK_OUT_DIRECTIONS, endpoint=False)
    for step in np.linspace(inside + BACK_OUT_SLACK, BACK_OUT + BACK_OUT_SLACK, 4):
        candidates = position[None, :2] + step * np.column_stack([np.cos(angles), np.sin(angles)])
        room = world.room(candidates) - radius - BACK_OUT_SLACK
        if room.max() >= 0.0:
            return np.asarray(candidates[int(np.argmax(room))], dtype=float)
    return position


def _from(position: FloatArray, path: OptimalPath) -> OptimalPath:
    """`path` with a straight piece from `position` to its start before it."""
    a = (float(position[0]), float(position[1]))
    b = (float(path.points[0][0]), float(path.points[0][1]))
    piece = PathPiece('line', a, b, math.dist(a, b))
    return replace(path, length=path.length + piece.length, points=np.vstack([np.array([a]), path.points]),
                   pieces=(piece, *path.pieces))


def parked_world(world: World, others: Sequence[OtherRobot], goal: FloatArray, radius: float,
                 params: PlannerParams) -> World | None:
    """The world with the robots standing still (not at this robot's goal) as circles; None if none is.

    They are inflated by what the guard adds for another robot (a tick's travel and a quarter margin), so a
    way round a parked robot is not one the guard stops on.
    """
    parked = [o for o in others if math.hypot(*o.velocity) < PARKED_SPEED
              and math.hypot(o.position[0] - goal[0], o.position[1] - goal[1]) > o.radius + radius]
    if not parked:
        return None
    reach = params.max_speed * params.dt + 0.25 * params.clearance_margin + 0.01
    return World(world.workspace, world.obstacle_list + tuple(
        Circle((float(o.position[0]), float(o.position[1])), o.radius + reach) for o in parked))


def robot_path(world: World, others: Sequence[OtherRobot], position: FloatArray, goal: FloatArray, radius: float,
               params: PlannerParams, turn_room: bool = False) -> tuple[OptimalPath | None, World]:
    """A robot's exact path round the obstacles and the robots parked (see parked_world), and the world it was
    planned in; round the obstacles alone when no way round the parked robots exists, (None, world) if none.

    The robot may already stand within a parked robot's inflation (it was held there): the path round them
    then starts with what it has, down to almost nothing, and moves away. Moving robots are left to the guard.
    """
    parked = parked_world(world, others, goal, radius, params)
    if parked is not None:
        path = exact_path(parked, position, goal, radius, params, turn_room=turn_room, floor=0.01)
        if path is not None:
            return path, parked
    return exact_path(world, position, goal, radius, params, turn_room=turn_room), world


def blocked_reason(world: World, position: FloatArray, goal: FloatArray, radius: float, waited: float,
                   timeout: float) -> str:
    """The status of a robot holding because what it believes has no way to the goal (Navigator.fail_no_path),
    naming what is in the way (in_the_way)."""
    return (f'blocked: no way to the goal in what the laser shows; in the way: '
            f'{in_the_way(world, position, goal, radius)}; planning again ({waited:.1f} of {timeout:g} s)')


def in_the_way(world: World, position: FloatArray, goal: FloatArray, radius: float) -> str:
    """The first obstacle within the radius of the straight run to the goal (else the one nearest the goal): its
    place and size, and for one the laser showed (a World perception made, perception.belief.BelievedWorld: its
    `seen_obstacles` are those, `map_obstacles` the map it started from) how far it lies from the map's obstacles: a
    wall seen a few centimetres beside a mapped one is the localization's error, one far from any a thing the map
    lacks."""
    start, end = np.asarray(position, dtype=float)[:2], np.asarray(goal, dtype=float)[:2]
    steps = int(min(max(math.ceil(math.dist(start, end) / 0.1), 1), 1000))
    run = start + np.linspace(0.0, 1.0, steps + 1)[:, None] * (end - start)
    if not len(world.obstacles):
        return 'nothing known'
    distances = world.obstacles.distances(run)                        # (points, obstacles)
    hit = np.flatnonzero(distances.min(axis=1) < radius)
    row = int(hit[0]) if len(hit) else len(run) - 1
    item = world.obstacles.items[int(np.argmin(distances[row]))]
    what = (f'a circle of radius {item.radius:.2f} m at ({item.center[0]:.2f}, {item.center[1]:.2f})'
            if isinstance(item, Circle) else
            f'a wall from ({item.start[0]:.2f}, {item.start[1]:.2f}) to ({item.end[0]:.2f}, {item.end[1]:.2f})')
    seen = getattr(world, 'seen_obstacles', None)
    if seen is None:
        return what
    if not any(item is o for o in seen):
        return f'{what}, on the map'
    mapped = Obstacles(getattr(world, 'map_obstacles', ()))
    if not len(mapped):
        return f'{what}, seen by the laser'
    ends = [item.center] if isinstance(item, Circle) else [item.start, item.end]
    gap = max(float(mapped.clearance(np.array(ends, dtype=float)).max()), 0.0)
    return f'{what}, seen by the laser, {"its centre" if isinstance(item, Circle) else "its ends up to"} ' \
        f'{gap:.2f} m from the nearest obstacle of the map'


class NoPathHold:
    """A robot planning in what its laser shows and finding no way to the goal: since when, and where it last
    looked. A belief can be wrong for a moment, so the goal fails only after blocked_timeout (Navigator.fail_no_path);
    meanwhile the search runs again on each new belief, at least every BLOCKED_RETRY s."""

    def __init__(self) -> None:
        self.since: float | None = None       # since when no path was found (None: a path was, or not looking)
        self._searched: World | None = None   # the world the last search found no path in, and when
        self._searched_at = -math.inf

    def reset(self) -> None:
        self.since = self._searched = None

    def skip_search(self, world: World, t: float) -> bool:
        """Held, the belief unchanged and the last search recent: no new search."""
        return self.since is not None and self._searched is world and t - self._searched_at < BLOCKED_RETRY

    def searched(self, world: World, t: float, found: bool) -> None:
        if found:
            self.reset()
        else:
            self._searched, self._searched_at = world, t

    def waited(self, t: float, timeout: float, from_scans: bool) -> float | None:
        """How long the robot has held for a path, now that none was found; None: the goal fails."""
        since = t if self.since is None else self.since
        if not from_scans or timeout <= 0.0 or t - since >= timeout:
            self.since = None
            return None
        self.since = since
        return t - since


def no_path_reason(radius: float, position: FloatArray, goal: FloatArray, world: World | None = None) -> str:
    """The failure of a goal with no path; `world`: what the robot believes, for one that plans in what its laser
    shows, to name what is in the way (in_the_way)."""
    reason = (f'no valid path: nothing keeps the robot radius {radius:g} m from the obstacles and the '
              f'border between ({position[0]:.3g}, {position[1]:.3g}) and the goal ({goal[0]:.3g}, {goal[1]:.3g})')
    return reason if world is None else f'{reason}; in the way: {in_the_way(world, position, goal, radius)}'


def solvable(scenario: Scenario) -> bool:
    """Does every robot of a scenario have an exact path keeping radius + clearance margin from the still
    obstacles, with the other robots parked at their goals? (The random worlds' admission test.)"""
    margin = scenario.planner.clearance_margin
    for i, spec in enumerate(scenario.robots):
        parked = [Circle((float(other.goal[0]), float(other.goal[1])), other.radius)
                  for j, other in enumerate(scenario.robots) if j != i]
        world = World(scenario.world.workspace, scenario.world.obstacle_list + tuple(parked))
        if shortest_path(world, spec.start[:2], spec.goal, spec.radius + margin) is None:
            return False
    return True
