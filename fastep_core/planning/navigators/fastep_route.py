"""FAStep-Route: FAStep-Kinematic guided by the exact shortest route over what the robot knows.

Why: FAStep-Kinematic measures d in eq. 10 to the goal, so its steps are greedy and lead into wedges and U-traps
whose way out lies behind the robot. What the robot knows (its map, the robots standing still) already fixes the
shortest way; only what moves is left for the swarm. Algorithm 1 with a route in place of the goal
(`FAStepRoute.choose_target`): the route (planning/shortest_path/optimal.py via `Navigator.exact_path`) is planned when
the goal is set and again only when `replan_reason` gives a reason (`replan` is the one method that plans); the target
is the farthest route vertex in sight; the kinematic controller drives there (eq. 12 / 13) unless another robot lies on
the run (eq. 11), when the swarm plans a step (eq. 3-10) with d measured to that vertex. Static obstacles therefore
never start the swarm. Before a one-lane passage (planning/safety/passage.py) the robot waits while another comes
through (`wait_before_passage`, at most PASSAGE_WAIT). The controller is aimed `lead` beyond the vertex so it keeps full
speed; progress along the route (a shorter way left) restarts the progress checker and trap detector. Cost: one exact
path per goal and replan, never per tick. Details and measurements: docs/fastep_route.md, "What it does".
"""

from __future__ import annotations

import math
import time
from typing import Sequence

import numpy as np

from fastep_core.geometry import point_segment_distance
from fastep_core.planning.navigator import FloatArray, Mode
from fastep_core.planning.navigators.fastep_kinematic import FAStepKinematic
from fastep_core.planning.others import OtherRobot, other_arrays, robots_on_run
from fastep_core.planning.safety.passage import Passage, passages, waiting_room
from fastep_core.planning.shortest_path.exact_path import PARKED_SPEED, robot_path
from fastep_core.planning.shortest_path.optimal import OptimalPath
from fastep_core.planning.shortest_path.route import SIGHT, SIGHT_VERTICES, Route, RouteSpeed
from fastep_core.world import World

__all__ = ['BLOCK_TIME', 'FAStepRoute', 'REPLAN_INTERVAL', 'Route', 'RouteSpeed', 'SIGHT', 'SIGHT_VERTICES',
           'TURN_ROOM_SLACK']

BLOCK_TIME = 1.0        # s: another robot standing on the route ahead this long makes the route go round it
CLEAR_TIME = 0.25       # s: the route free of standing robots this long ends that wait (a retried step is shorter)
REPLAN_INTERVAL = 1.0   # s: the route is planned at most this often for robots (blocking, or gone)
PASSAGE_LOOK = 15.0     # m: passages whose entry is this near along the route are watched for oncoming robots
PASSAGE_WAIT = 30.0     # s: a robot waits before one passage at most this long (one that never comes through)
PASSAGE_WINDOW = 60.0   # m of route ahead measured for passages at a time
PASSAGE_SAME = 1.0      # m: a passage whose entry moved less than this (measured again) is the one waited before
PASSAGE_BEHIND = 5.0    # m of route behind the robot measured too (a robot backing up does not measure anew)
RADII_INTERVAL = 1.0    # s between looks for a larger robot than the passages were measured for
MOVED = 0.5             # m: a robot the route was planned round has moved away once it is this far from there
TURN_ROOM_SLACK = 0.03  # a robot that cannot turn in place takes the route with turn room if at most 3 % longer
class FAStepRoute(FAStepKinematic):
    """Algorithm 1 toward the farthest route vertex in sight; the swarm only where other robots block the run."""

    method = 'fastep_route'
    route: Route | None = None   # the route being followed (None before the first tick and once arrived)
    replans = 0                  # routes planned after the first one
    route_time = 0.0             # wall seconds spent in exact paths (the first route, replans, escapes)
    replan_log: list[tuple[float, str]]   # (t, reason) of every replan
    # What set_goal sets, read before any goal too (a planning pass of an idle planner node asks for speed_law).
    _vertex: FloatArray | None = None
    _aim: FloatArray | None = None

    def set_goal(self, goal: Sequence[float], t: float = 0.0, heading: float | None = None) -> None:
        super().set_goal(goal, t, heading)
        self.route, self.replans, self.route_time, self.replan_log = None, 0, 0.0, []
        self._vertex: FloatArray | None = None        # the route target (identity tells a new one)
        self._aim: FloatArray | None = None           # what the controller is aimed at for it
        self._looked_at: FloatArray | None = None     # where the robot was when the target was last looked for
        self._look_after = 0.0                        # ... and how far it may drive before the next look
        self._blocked_since: float | None = None      # since when a robot has stood on the route ahead
        self._clear_since: float | None = None        # since when none has, while the wait goes on
        # The passage waited before last: its entry (x, y), since when, and whether this robot waited last tick.
        self._waited: tuple[float, float, float, bool] | None = None
        self._replanned_at = -math.inf
        self._route_best = math.inf                   # the shortest route left so far (progress)
        self._route_tick = -1                         # the last tick that planned a route

    # ---------------------------------------------------------------- the route
    def replan(self, position: FloatArray, others: Sequence[OtherRobot], reason: str) -> bool:
        """Plan the route from position round the obstacles and the robots standing still; False (and failed)
        when there is none."""
        path = self.exact_path(position, others)
        t = self._last_t or 0.0
        if path is None:
            self.fail_no_path(position)
            return False
        self.replans += 1
        self.replan_log.append((t, reason))
        self._install(path, self.path_world, self._parked(others))
        self._replanned_at = t
        return True

    def exact_path(self, position: FloatArray, others: Sequence[OtherRobot] = ()) -> OptimalPath | None:
        """The exact path (the goal's first tick, replans, trap escapes), its wall time counted.

        For a robot that cannot turn in place the base class takes the path with TURN_ROOM more clearance
        whenever there is one, however much longer (a way round a whole cluster of circles instead of through a
        gap it fits). Here it is taken only when it is at most TURN_ROOM_SLACK longer than the path keeping the
        usual clearance; else the robot takes the gap and leaves tight corners to its manoeuvres.
        """
        start = time.perf_counter()
        self._route_tick = self._ticks
        path = super().exact_path(position, others)
        assert self.goal is not None
        # No path is shorter than the straight line: a roomy path within TURN_ROOM_SLACK of it (with a rounding
        # margin far beyond the floats' error) is taken whatever the tight one would be, so that one is not searched.
        straight = math.hypot(float(self.goal[0]) - float(position[0]), float(self.goal[1]) - float(position[1]))
        if path is not None and not self.model.turns_in_place and path.clearance > self.clearance and \
                path.length > (1.0 + TURN_ROOM_SLACK) * straight * (1.0 - 1e-9):
            roomy_world = self.path_world
            tight, tight_world = robot_path(self.world, others, position, self.goal, self.radius, self.params)
            if tight is not None and path.length > (1.0 + TURN_ROOM_SLACK) * tight.length:
                path, self.path_world = tight, tight_world
            else:
                self.path_world = roomy_world
        self.route_time += time.perf_counter() - start
        return path

    def step_budget(self) -> int | None:
        """With a budget per tick (params.step_iterations), a tick that planned a route runs no swarm iteration (a new
        plan only its initial swarm): its step goes on next tick (a route and a step plan in one tick were the
        slowest ticks left, 3-5 ms). Never two such ticks in a row (plan_next_step): routes every tick would
        otherwise keep the step from ever ending."""
        budget = super().step_budget()
        return 0 if budget is not None and self._route_tick == self._ticks else budget

    def _install(self, path: OptimalPath, world: World, parked: FloatArray) -> None:
        self.route = Route.from_path(path, world, self.world, parked)
        self._route_points = path.points                          # with its start: passages are measured on it
        start, first = path.points[0], self.route.vertices[0]
        self._route_length = float(self.route.rest[0]) + math.hypot(float(first[0]) - float(start[0]),
                                                                    float(first[1]) - float(start[1]))
        # (other robots' radius, from and to where along the route it was measured, the passages found there)
        self._passages: tuple[float, float, float, list[Passage]] | None = None
        self._radii_seen = -math.inf                                # when the other robots' radii were last looked at
        self._vertex = self._aim = self._looked_at = None
        self._blocked_since = self._clear_since = None
        self._route_best = math.inf   # progress is measured along the new route from here on

    def _parked(self, others: Sequence[OtherRobot]) -> FloatArray:
        """Centres of the other robots standing still (not at this robot's goal): what the route goes round."""
        if not others or self.goal is None:
            return np.zeros((0, 2))
        centres, velocities, radii = other_arrays(others)
        still = (np.hypot(*velocities.T) < PARKED_SPEED) & \
            (np.hypot(*(centres - self.goal).T) > radii + self.radius)
        parked: FloatArray = centres[still]
        return parked

    def replan_reason(self, t: float, position: FloatArray, others: Sequence[OtherRobot]) -> str | None:
        """Why the route must be planned again now, or None: what the robot knows has changed.

        The world given to the navigator is checked every tick; robots (one standing on the route ahead for
        BLOCK_TIME, one the route went round gone) at most every REPLAN_INTERVAL.
        """
        route = self.route
        assert route is not None
        if route.base is not self.world:
            if not route.adopt(self.world, position, self.params.clearance_margin):
                return 'the world changed'
            self._passages, self._looked_at = None, None   # measured in the world before
        blocked = bool(others) and self._robot_on_route(position, others)
        if blocked:
            self._clear_since = None
            if self._blocked_since is None:
                self._blocked_since = t
        elif self._blocked_since is not None:
            # Two robots that hold each other up twitch: each retries its step every RETRY_AFTER, and the move of
            # one tick makes it a moving robot for the other. Only a route free for CLEAR_TIME ends the wait: else
            # it restarted every half second, neither routed round the other, and they stood face to face until
            # the trap detector fired (multi_robot:1000010, 18 s; docs/clutter.md).
            if self._clear_since is None:
                self._clear_since = t
            if t - self._clear_since >= CLEAR_TIME:
                self._blocked_since = self._clear_since = None
        if t - self._replanned_at < REPLAN_INTERVAL:
            return None
        if len(route.parked):
            centres = other_arrays(others)[0] if others else np.zeros((0, 2))
            if not len(centres) or (np.hypot(*(route.parked[:, None, :] - centres[None]).transpose(2, 0, 1))
                                    .min(axis=1) > MOVED).any():
                return 'a robot the route went round has moved'
        if blocked and self._blocked_since is not None and t - self._blocked_since >= BLOCK_TIME:
            return 'a robot stands on the route'
        return None

    def _robot_on_route(self, position: FloatArray, others: Sequence[OtherRobot]) -> bool:
        """Does a robot standing still (not at this robot's goal) lie on the route ahead, within both radii
        plus half the margin, and not already planned round?"""
        route = self.route
        assert route is not None and self.goal is not None
        centres, velocities, radii = other_arrays(others)
        still = (np.hypot(*velocities.T) < PARKED_SPEED) & \
            (np.hypot(*(centres - self.goal).T) > radii + self.radius)
        if not still.any():
            return False
        ahead = np.vstack([position, route.stacked[route.index:route.index + SIGHT_VERTICES]])
        gaps = point_segment_distance(centres[still][:, None, :], ahead[None, :-1], ahead[None, 1:]).min(axis=1) \
            if len(ahead) > 1 else np.hypot(*(centres[still] - position).T)
        on = gaps < radii[still] + self.radius + 0.5 * self.params.clearance_margin
        if not on.any() or not len(route.parked):
            return bool(on.any())
        known = np.hypot(*(centres[still][on][:, None, :] - route.parked[None]).transpose(2, 0, 1)).min(axis=1) <= MOVED
        return bool((~known).any())

    def route_target(self, position: FloatArray, t: float, others: Sequence[OtherRobot]) -> FloatArray | None:
        """The farthest route vertex in sight; the route is planned again when none is (at most every
        REPLAN_INTERVAL: a fresh route's first vertex counts as seen).

        It is looked for again after `_look_after` metres of travel (see `next_look`), and at once when the
        robot drove anything else than the route target's aim last tick (a swarm step, an escape, a backup).
        """
        route = self.route
        assert route is not None
        looked = self._looked_at
        if self._vertex is not None and looked is not None and self._aim is not None and self._target is self._aim \
                and math.hypot(position[0] - looked[0], position[1] - looked[1]) < self._look_after \
                and not self._past_goal(position):
            return self._vertex
        index = route.in_sight(position, self.radius, self.params.clearance_margin)
        if index is None:
            if t - self._replanned_at >= REPLAN_INTERVAL or self._replanned_at == -math.inf:
                if not self.replan(position, others, 'no route vertex in sight'):
                    return None
                route = self.route
                assert route is not None
                index = route.in_sight(position, self.radius, self.params.clearance_margin)
            index = route.index if index is None else index   # a fresh route's first vertex is reachable
        route.passing(position, self.params.waypoint_tolerance)
        index = route.index
        self._vertex, self._aim = route.vertices[index], None   # aimed afresh from where the robot is
        self._looked_at = position.copy()
        self._look_after = self.next_look(position, self._vertex)
        return self._vertex

    def _past_goal(self, position: FloatArray) -> bool:
        """Has the robot gone past the goal it is aimed beyond? Then it is aimed afresh from where it is: the speed
        law allows nothing past the goal, and a robot a late control tick carried past it (on a loaded computer)
        stood there for good, 0.3 m from its goal."""
        aim, vertex, route = self._aim, self._vertex, self.route
        if aim is None or vertex is None or route is None or vertex is not route.vertices[-1]:
            return False
        return float((vertex[0] - position[0]) * (aim[0] - position[0])
                     + (vertex[1] - position[1]) * (aim[1] - position[1])) <= 0.0

    def next_look(self, position: FloatArray, vertex: FloatArray) -> float:
        """Metres of travel before the farthest vertex in sight is looked for again.

        detection_interval, as eq. 11's detection runs. A holonomic robot drives the straight run to the vertex,
        along which the vertex stays in sight (a part of a free run is free): while it is farther than
        sensing_range, half of what lies beyond that is driven before the next look (a vertex past a bend comes
        into sight only near the bend), and the goal, once in sight, is never looked for again.
        """
        interval = self.params.detection_interval
        if not self.model.holonomic:
            return interval
        assert self.route is not None
        if vertex is self.route.vertices[-1]:
            return math.inf
        gap = math.hypot(vertex[0] - position[0], vertex[1] - position[1])
        return max(interval, 0.5 * (gap - self.params.sensing_range))

    def step_target(self) -> FloatArray:
        """d in eq. 10 is measured to the route target."""
        assert self.goal is not None
        return self._vertex if self._vertex is not None else self.goal

    def aim_route(self, position: FloatArray, vertex: FloatArray) -> FloatArray:
        """What the controller is aimed at for the route target (see the module's "Speed")."""
        assert self.route is not None
        if vertex is self.route.vertices[-1] and not self.params.regulated_speed:
            return vertex                      # the goal: the paper's approach
        run = vertex - position
        gap = math.hypot(run[0], run[1])
        if gap < 1e-9:
            return vertex
        p, top = self.params, self.limits.max_speed
        gain = min(p.alpha1, p.alpha2) if self.model.holonomic else p.speed_gain
        lead = top / gain if top > 0.0 else p.waypoint_lead
        return vertex if lead <= 0.0 else vertex + run * (lead / gap)

    def speed_law(self) -> RouteSpeed | None:
        """What regulates the speed now (params.regulated_speed): the route, the vertex aimed at and the goal as
        they are, frozen, so the control loop can regulate between passes while the next pass replans."""
        route, vertex, goal = self.route, self._vertex, self.goal
        if not self.params.regulated_speed or route is None or goal is None or vertex is None:
            return None
        return RouteSpeed(route.stacked, route.rest, route.index, vertex, self._aim, goal.copy(),
                          vertex is route.vertices[-1], self.radius, self.params, self.world,
                          bool(self.model.holonomic), route.clearance_at, self.measured_base.braking, self.limits)

    def speed_allowed(self, position: FloatArray, dt: float) -> float:
        """RouteSpeed.allowed of the route as it is now (max_speed, or what the way allows: the module's "Speed")."""
        law = self.speed_law()
        return self.limits.max_speed if law is None else law.allowed(position, dt)

    # -------------------------------------------------------------- Algorithm 1
    def choose_target(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        assert self.goal is not None
        t = self._last_t or 0.0
        if self.route is None:                 # the goal's first tick: the base class's path is the first route
            if self.reference is None:
                if not self.replan(position, others, 'goal set'):
                    return None
            else:
                self._install(self.reference, self.world, np.zeros((0, 2)))
        else:
            reason = self.replan_reason(t, position, others)
            if reason is not None and not self.replan(position, others, reason):
                return None
        vertex = self.route_target(position, t, others)
        if vertex is None:
            return None
        self.note_progress(position, t)
        following = self.keep_waypoint(position, others)     # a swarm waypoint not yet reached
        self.committed = self.committed and following
        if self.committed:                                  # a step that broke a hold is driven to its end
            return self.waypoint
        if others and self.wait_before_passage(position, t, others):
            return None
        if not robots_on_run(others, self.radius, position, vertex, self.params.sensing_range,
                             0.5 * self.params.clearance_margin):
            self.waypoint, self.cost, self.mode, self.reason = None, 0.0, Mode.KINEMATIC, 'following the route'
            if self._aim is None:
                self._aim = self.aim_route(position, vertex)
            return self._aim
        if following:
            return self.aim(position, self.waypoint)
        waypoint = self.plan_next_step(position, others)     # eq. 3-10 toward the route target
        if waypoint is not None and self.params.stuck_steps > 0:
            self.note_stuck(position, waypoint, others)
        return None if waypoint is None else self.aim(position, waypoint)

    def wait_before_passage(self, position: FloatArray, t: float, others: Sequence[OtherRobot]) -> bool:
        """Stand before a one-lane passage ahead while another robot comes through it (planning/safety/passage.py);
        True (and the status says so) while waiting, at most PASSAGE_WAIT seconds for one passage (a replan
        does not restart that). The progress checker and the trap detector wait too."""
        route = self.route
        assert route is not None and self.goal is not None
        waited = self._waited
        if waited is not None:
            self._waited = (waited[0], waited[1], waited[2], False)
        found = self._passages
        other_radius = -1.0 if found is None else found[0]
        if found is None or t - self._radii_seen >= RADII_INTERVAL:
            # The largest robot known, looked for at most every RADII_INTERVAL (iterating over the others every
            # tick was most of this method's cost): a larger one measures the passages again.
            self._radii_seen = t
            other_radius = max((o.radius for o in others if not o.mover and math.isfinite(o.radius)), default=-1.0)
            if other_radius < 0.0:
                return False
        length = self._route_length
        along = length - route.remaining(position)                 # metres along the route, from its start
        if found is None or found[0] < other_radius or along < found[1] or \
                (along + PASSAGE_LOOK > found[2] and found[2] < length):
            found = self._measure_passages(max(0.0, along - PASSAGE_BEHIND), max(other_radius, 0.0), length)
        passage = next((p for p in found[3] if p.exit > along), None)
        if passage is None or passage.entry - along > PASSAGE_LOOK:
            return False                          # none left, or the next one is far: drive on
        if passage.entry <= along:
            return False                          # inside it already: drive on
        # The same passage as waited before, give or take the sampling of a new measurement or a new route.
        entry = passage.points[0]
        same = waited is not None and \
            math.hypot(waited[0] - float(entry[0]), waited[1] - float(entry[1])) < PASSAGE_SAME
        if waited is not None and same and t - waited[2] > PASSAGE_WAIT:
            return False
        robots = [o for o in others if not o.mover]
        other = passage.conflict(position, self.name, robots, PARKED_SPEED, self.radius,
                                 self.params.clearance_margin, waited is not None and same and waited[3])
        if other is None or passage.entry - along > waiting_room(self.radius, other.radius,
                                                                 self.params.clearance_margin):
            return False                          # free, or not there yet: drive on towards it
        since = waited[2] if waited is not None and same else t
        self._waited = (float(entry[0]), float(entry[1]), since, True)
        self.waypoint, self.cost = None, 0.0
        self.mode, self.reason = Mode.KINEMATIC, f'waiting for {other.name} to come through the passage'
        self.progress.made_progress(t)
        self.trap.reset(t, math.hypot(self.goal[0] - position[0], self.goal[1] - position[1]))
        return True

    def _measure_passages(self, start: float, other_radius: float,
                          length: float) -> tuple[float, float, float, list[Passage]]:
        """The passages of the route from `start` metres along it, PASSAGE_WINDOW metres on (further while the
        last one found runs on to the window's end), kept until the robot nears the window's end."""
        stop = start + PASSAGE_WINDOW
        while True:
            found = passages(self.world, self._route_points, self.radius, other_radius,
                             self.params.clearance_margin, start, stop)
            if not found or found[-1].exit < min(stop, length) - 1e-9 or stop >= length:
                break
            stop += PASSAGE_WINDOW
        self._passages = (other_radius, start, stop, found)
        return self._passages

    def note_progress(self, position: FloatArray, t: float) -> None:
        """A route left progress_distance shorter than ever restarts the progress checker and the trap detector."""
        assert self.route is not None and self.goal is not None
        left = self.route.remaining(position)
        if self._route_best == math.inf:
            self._route_best = left
        elif left < self._route_best - self.params.progress_distance:
            self._route_best = left
            self.progress.made_progress(t)
            self.trap.reset(t, math.hypot(self.goal[0] - position[0], self.goal[1] - position[1]))
