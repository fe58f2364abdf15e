"""FAStep-Kinematic and the ACO-Kinematic baseline: the per-robot decision loop.

A navigator is called once per control tick with the robot's state and the other robots it knows of, and
returns the command for the robot's kinematic model. The same object runs inside `fastep-sim` and inside the
ROS planner node, so a live run and an offline run take the same decisions.

FAStep-Kinematic (paper, Algorithm 1 and Fig. 1):
1. While nothing blocks the straight run to the goal, the kinematic controller drives the robot to the goal.
2. An obstacle is detected when its surface is nearer than `sensing_range` (eq. 11, epsilon) *and* the straight
   run to the goal passes closer to it than the robot's clearance: only obstacles on the way count (Fig. 2).
   Another robot is detected the same way, with the sum of both radii as its clearance (case study 2).
3. On detection the swarm plans one step (a waypoint within `step_radius`); the controller drives the robot
   there. At the waypoint, or as soon as the run to the goal is clear again, the loop goes back to step 1/2.
ACO-Kinematic plans every step with continuous ACO, whether anything is in the way or not, with the same
fitness, clearance rule and step radius, and drives straight to the goal only for the last step.

Safety nets surround the planner, as a navigation stack needs:
- A guard stops any motion that would bring the robot's centre within its radius of an obstacle or within the
  sum of radii (plus the other robot's travel in one tick) of another robot.
- A goal with no path at all (walled in, or behind a gap narrower than the robot) is refused on the first
  tick with 'no valid path', from the exact planner (planning/optimal.py), instead of wandering until a timeout.
- Trap escape: greedy steps (stay far from obstacles, get closer to the goal) settle in local minima such as
  the inside of a U-shaped wall. When the robot has not come `progress_distance` closer to the goal within
  `trap_timeout` seconds, it follows the exact shortest path out (planning/escape.py), round robots parked at
  their goals too, and hands back to the algorithm once it is `progress_distance` closer to the goal
  than it ever was in the trap (the leave rule of the Bug algorithms). Each escape ends strictly closer to the
  goal, so escapes cannot cycle.
- Tractor-trailer manoeuvres: a forward-steered vehicle cannot follow a point path out of a tight corner. A
  trapped tractor-trailer, or one the guard keeps stopped (1 s at a wall, 3 s at another robot), drives a
  manoeuvre instead: a hybrid-A* search over its own forward and reverse arcs (planning/manoeuvre.py) to where
  the goal is in clear sight ahead, replayed tick by tick and planned again if the robot drifts off it.
- Backup recovery: a point mass the guard keeps stopped moves straight away from what is nearest for
  BACKUP_TIME seconds; a tractor-trailer whose manoeuvre search found nothing, the move (back or forward,
  straight or at full lock) that gains the most room without folding its trailer.
- A progress checker fails the run when the robot does not come `progress_distance` closer to the goal (or
  `progress_distance` shorter on its escape path) within `progress_timeout` seconds.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from enum import Enum
from typing import Protocol, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import Circle, point_segment_distance
from fastep_core.kinematics import PointMass, PointMassController, TractorTrailer, TractorTrailerController
from fastep_core.kinematics.tractor_trailer import hitch_angle, wrap_angle
from fastep_core.planning.escape import EscapePath
from fastep_core.planning.manoeuvre import Manoeuvre, plan_manoeuvre
from fastep_core.planning.optimal import OptimalPath, shortest_path
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.step import StepProblem, plan_step
from fastep_core.world import World

__all__ = ['ACOKinematic', 'FAStepKinematic', 'Mode', 'Navigator', 'OtherRobot', 'make_navigator',
           'make_robot']

FloatArray = NDArray[np.float64]
HOLD_BEFORE_STEP = 1.0  # seconds a robot waits for another before stepping around it
RETRY_AFTER = 0.5       # seconds between step-planning attempts while no feasible step exists
BACKUP_SPEED = 0.25     # m/s of the backing-up recovery ...
BACKUP_TIME = 4.0       # ... for this many seconds (1 m), after the guard held the robot for HOLD_BEFORE_STEP
MAX_RECOVERY_HITCH = 1.0  # rad: a recovery move may not fold the trailer beyond this (or beyond where it is)
TURN_ROOM = 1.0         # extra clearance (m) of a tractor-trailer's exact path, where there is room for it
PARKED_SPEED = 0.05     # m/s: another robot slower than this is planned around like an obstacle
PATH_SPACING = 0.25     # metres between exact-path vertices along arcs (escape paths, the optimal reference)
OFF_MANOEUVRE = 0.3     # m or rad: a tractor-trailer this far off its manoeuvre's states plans it again


class Mode(str, Enum):
    """What a navigator is doing; the value is what the ROS status topic reports."""

    IDLE = 'idle'            # no goal yet
    KINEMATIC = 'kinematic'  # driving straight to the goal by the kinematic equations
    AVOIDING = 'avoiding'    # driving to a waypoint planned by the swarm
    ARRIVED = 'arrived'
    FAILED = 'failed'


@dataclass(frozen=True)
class OtherRobot:
    """Another robot as a moving obstacle: where it is, how fast it goes, how big it is."""

    name: str
    position: tuple[float, float]
    velocity: tuple[float, float] = (0.0, 0.0)
    radius: float = 0.5


class Model(Protocol):
    state_size: int

    def integrate(self, state: FloatArray, command: FloatArray, dt: float) -> FloatArray: ...

    def velocity(self, state: FloatArray, command: FloatArray) -> FloatArray: ...


class Controller(Protocol):
    def reset(self, state: FloatArray, target: FloatArray) -> None: ...

    def command(self, state: FloatArray, target: FloatArray, dt: float) -> FloatArray: ...


class RobotLike(Protocol):
    model: str
    length: float
    trailer_length: float
    hitch_offset: float


def make_robot(spec: RobotLike, params: PlannerParams) -> tuple[Model, Controller]:
    """The kinematic model and controller for a scenario robot ('point_mass' or 'tractor_trailer')."""
    if spec.model == 'point_mass':
        return PointMass(), PointMassController(params.alpha1, params.alpha2, params.max_speed)
    if spec.model == 'tractor_trailer':
        model = TractorTrailer(spec.length, spec.trailer_length, spec.hitch_offset)
        return model, TractorTrailerController(model, params.speed_gain, params.max_speed)
    raise ValueError(f'unknown robot model {spec.model!r}')


class Navigator:
    """The loop shared by both algorithms; subclasses decide when a step is planned."""

    method = 'fastep'        # the algorithm's name
    step_method = 'fastep'   # the optimizer that plans a step (plan_step's `method`)
    escapes_traps = True     # False for a navigator that already follows the exact path

    def __init__(self, model: Model, controller: Controller, radius: float, world: World,
                 params: PlannerParams | None = None, rng: np.random.Generator | int | None = None) -> None:
        self.model = model
        self.controller = controller
        self.radius = float(radius)
        self.world = world
        self.params = params or PlannerParams()
        self.rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
        self.goal: FloatArray | None = None
        self.mode = Mode.IDLE
        self.reason = 'waiting for a goal'
        self.waypoint: FloatArray | None = None
        self.plan: list[FloatArray] = []
        self.cost = 0.0
        self.activations = 0
        self.plan_time = 0.0   # wall seconds spent inside the step optimizer
        self._target: FloatArray | None = None
        self._last_t: float | None = None
        self._best_distance = math.inf
        self._best_time = 0.0
        self._detection: tuple[FloatArray, FloatArray, bool] | None = None  # (position, target, blocked)
        self._free_disc: tuple[FloatArray, float] | None = None  # (centre, radius) known obstacle-free
        self._held_since: float | None = None  # when the guard started holding the robot for another robot
        self._committed = False  # follow the current waypoint to the end (a step taken to break a hold)
        self._retry_at = -math.inf  # no step planning before this time (after a failed attempt)
        self._stuck_since: float | None = None  # since when the guard has stopped the robot without a break
        self._backup_until = -math.inf     # backing up (the recovery from being stuck) until this time ...
        self._backup_command: FloatArray | None = None  # ... with this command (a tractor-trailer's choice)
        self.reference: OptimalPath | None = None  # the exact shortest path, computed when the goal is taken
        self.escapes = 0                   # trap escapes started
        self._path_checked = False         # has the goal been checked for a path (first tick after set_goal)
        self._trap_distance = math.inf     # trap checker: best distance to the goal since the last reset ...
        self._trap_time = 0.0              # ... and when it was reached
        self._escape: EscapePath | None = None   # the way out of a trap, while escaping
        self._escape_best = math.inf       # the shortest remaining path length so far (progress on an escape)
        self._escape_planned_at = -math.inf  # when the escape path was last planned
        self.path_world = world            # the world the last exact_path was planned in
        self._escape_exit = 0.0            # hand back to the algorithm once this close to the goal
        self.manoeuvres = 0                # tractor-trailer manoeuvres started (planning/manoeuvre.py)
        self._manoeuvre: Manoeuvre | None = None  # the manoeuvre being driven ...
        self._manoeuvre_tick = 0           # ... and the tick of it that comes next
        self._manoeuvre_retry_at = -math.inf  # no manoeuvre search before this time (after a failed one)
        self._manoeuvre_left_at = math.inf    # distance to the goal where the last manoeuvre ended
        self._manoeuvre_held_since: float | None = None  # since when the guard holds the manoeuvre

    # ----------------------------------------------------------------- goals
    @property
    def clearance(self) -> float:
        """Distance a planned waypoint keeps from every obstacle surface."""
        return self.radius + self.params.clearance_margin

    def set_goal(self, goal: Sequence[float], t: float = 0.0) -> None:
        """Accept a new goal (raises GoalError if it is outside the map, occupied or not finite)."""
        self.world.check_point(goal, self.radius)
        self.goal = np.array([float(goal[0]), float(goal[1])])
        self.mode = Mode.KINEMATIC
        self.reason = 'goal accepted'
        self.waypoint = None
        self.plan = []
        self.cost = 0.0
        self._target = None
        self._best_distance = math.inf
        self._best_time = t
        self.reference = None
        self._path_checked = False
        self._trap_distance, self._trap_time = math.inf, t
        self._escape = None
        self._manoeuvre = None
        self._manoeuvre_retry_at = -math.inf
        self._manoeuvre_left_at = math.inf
        self._committed = False

    def fail(self, reason: str) -> None:
        self.mode = Mode.FAILED
        self.reason = reason
        self.waypoint = None
        self._target = None
        self.cost = 0.0

    @property
    def target(self) -> FloatArray | None:
        """The point the robot is driving to now: a waypoint or the goal."""
        return self._target

    # ------------------------------------------------------------- the loop
    def update(self, t: float, state: FloatArray, others: Sequence[OtherRobot] = ()) -> FloatArray:
        """One control tick: returns the command for the model (zeros when stopped)."""
        stop = np.zeros(2)
        dt = self.params.dt if self._last_t is None or t <= self._last_t else t - self._last_t
        self._last_t = t
        if self.goal is None or self.mode in (Mode.ARRIVED, Mode.FAILED):
            return stop
        state = np.asarray(state, dtype=float)
        if not all(map(math.isfinite, state)):
            self.reason = 'robot state is not finite; holding still'
            return stop
        position = state[:2]
        others = [o for o in others if math.isfinite(o.position[0]) and math.isfinite(o.position[1])]
        distance = math.hypot(self.goal[0] - position[0], self.goal[1] - position[1])
        if distance <= self.params.goal_tolerance:
            self.mode, self.reason, self.waypoint, self.cost = Mode.ARRIVED, 'goal reached', None, 0.0
            self._target = None
            return stop
        if not self._path_checked:
            self._path_checked = True
            self.reference = self.exact_path(position)
            if self.reference is None:
                self.fail(self.no_path_reason(position))
                return stop
        if distance < self._best_distance - self.params.progress_distance or self._best_distance == math.inf:
            self._best_distance, self._best_time = distance, t
        elif self.params.progress_timeout > 0 and t - self._best_time > self.params.progress_timeout:
            self.fail(f'failed to make progress: not {self.params.progress_distance:g} m closer to the goal '
                      f'in {self.params.progress_timeout:g} s')
            return stop
        if self.trapped(t, distance):
            # A tractor-trailer leaves a trap by a manoeuvre of its own motions; a point mass (or a
            # tractor-trailer whose search found none) along the exact shortest path.
            if self.model.state_size == 4 and self.start_manoeuvre(state, t, others):
                self.escapes += 1
            elif not self.start_escape(position, distance, t, others):
                return stop
        if self._manoeuvre is not None:
            command = self.drive_manoeuvre(state, t, dt, distance, others)
            if command is not None:
                return command

        if t < self._backup_until:
            return self.back_up(state, dt, others)
        # Two robots the guard holds for each other wait forever if each still sees its own way as clear:
        # after `HOLD_BEFORE_STEP` seconds the held robot plans a step around the other instead.
        held_too_long = self._held_since is not None and t - self._held_since >= HOLD_BEFORE_STEP
        if held_too_long:
            self._held_since = None
            target = self.plan_next_step(position, others)
            self._committed = target is not None
        else:
            target = self.follow_escape(position, distance, t, others) if self._escape is not None else None
            if self.mode is Mode.FAILED:
                return stop
            if self._escape is None:
                target = self.choose_target(position, others)
        if target is None:
            self._target = None
            return stop
        # Targets are the goal or a waypoint array, never changed in place: identity tells a new target.
        if target is not self._target:
            self.controller.reset(state, target)
            self._target = target
        command = self.controller.command(state, target, dt)
        guarded = self.guard(state, command, dt, others)
        if guarded is command:
            self._held_since = self._stuck_since = None
            return guarded
        if self._held_since is None and self.reason.startswith('stopped: giving way'):
            self._held_since = t
        # A tractor-trailer turns only while moving, so a target behind it next to a wall (or a parked robot)
        # pins it there: after HOLD_BEFORE_STEP seconds stopped at a wall, or three times that at a robot (the
        # hold breaker's step has had its chance), it backs up (Nav2's backup recovery) to get room.
        if self._stuck_since is None:
            self._stuck_since = t
        patience = HOLD_BEFORE_STEP * (1.0 if self.reason.startswith('stopped: an obstacle') else 3.0)
        if t - self._stuck_since >= patience:
            self._stuck_since = None
            self._target = None   # the controller starts afresh after the recovery
            if self.model.state_size == 4 and self.start_manoeuvre(state, t, others):
                return guarded    # the manoeuvre drives from the next tick
            self._backup_until, self._backup_command = t + BACKUP_TIME, None
        return guarded

    def _room(self, points: FloatArray, others: Sequence[OtherRobot]) -> FloatArray:
        """Free room at points (n, 2): distance to the nearest obstacle surface or other robot's body."""
        room = self.world.obstacles.clearance(points) if len(self.world.obstacles) else np.full(len(points), 1e9)
        for other in others:
            room = np.minimum(room, np.hypot(*(points - np.asarray(other.position)).T) - other.radius)
        return room

    def _tractor_recovery(self, state: FloatArray, dt: float, others: Sequence[OtherRobot]) -> FloatArray:
        """Of straight back and forward or back at full lock either way, the move that gains the most room over
        the recovery without folding the trailer (hitch angle over MAX_RECOVERY_HITCH) and whose first step
        the guard allows: a wall alongside pins straight moves too, and reversing a trailer far folds it.
        When every move would fold it, straight back (the first option) all the same: cutting moves short
        instead kept trailers straighter but landed fewer robots (docs/robustness.md, "Tractor-trailers before
        manoeuvres")."""
        lock = BACKUP_SPEED * math.tan(7.0 / 18.0 * math.pi) / max(getattr(self.model, 'length', 1.0), 1e-6)
        options = [np.array([v, w]) for v in (-BACKUP_SPEED, BACKUP_SPEED) for w in (0.0, -lock, lock)]
        scores = []
        for option in options:
            if self.guard(state, option, dt, others) is not option:
                scores.append(-math.inf)
                continue
            probe, folds = state, False
            for _ in range(int(round(BACKUP_TIME / dt))):
                probe = self.model.integrate(probe, option, dt)
                folds = folds or abs(hitch_angle(probe)) > max(MAX_RECOVERY_HITCH, abs(hitch_angle(state)))
            scores.append(-math.inf if folds else float(self._room(probe[None, :2], others)[0]))
        return options[int(np.argmax(scores))]

    def back_up(self, state: FloatArray, dt: float, others: Sequence[OtherRobot]) -> FloatArray:
        """The recovery command: a tractor-trailer's best move (see _tractor_recovery), or for a point mass
        straight away from what is nearest; the guard still applies, and the recovery ends where it stops."""
        if self.model.state_size == 4:
            command = self._backup_command
            if command is None:
                command = self._backup_command = self._tractor_recovery(state, dt, others)
        else:
            h = 1e-4
            probes = state[:2] + np.array([[h, 0.0], [-h, 0.0], [0.0, h], [0.0, -h]])
            room = self._room(probes, others)
            away = np.array([room[0] - room[1], room[2] - room[3]])
            norm = float(np.hypot(*away))
            command = away * (BACKUP_SPEED / norm) if norm > 0 else np.zeros(2)
        guarded = self.guard(state, command, dt, others)
        if guarded is not command:
            self._backup_until = -math.inf
        else:
            self.reason = 'backing up: stuck'
        return guarded

    def choose_target(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        raise NotImplementedError

    # ------------------------------------------------ tractor-trailer manoeuvres
    def start_manoeuvre(self, state: FloatArray, t: float, others: Sequence[OtherRobot]) -> bool:
        """Search a manoeuvre (planning/manoeuvre.py) from state to where the goal is in clear sight ahead.

        It keeps the radius plus a quarter margin from the obstacles and robots parked (those the guard
        leaves; a robot already nearer gets no nearer), and no tick of it gets nearer within the radius, which
        the guard would stop; False, and no search for 5 s, if none is found.
        """
        assert self.goal is not None and isinstance(self.model, TractorTrailer)
        if t < self._manoeuvre_retry_at:
            return False
        world = self.parked_world(others) or self.world
        keep = self.radius + 0.25 * self.params.clearance_margin
        # A manoeuvre ends where the goal is in clear sight; if kinematic driving from there got stuck again
        # before coming progress_distance nearer, "in sight" was not enough (it had looped hundreds of times in
        # a soak scenario): this one goes on until the goal is within reach.
        distance = math.hypot(self.goal[0] - state[0], self.goal[1] - state[1])
        again = distance > self._manoeuvre_left_at - self.params.progress_distance
        clear_within = math.inf if again else self.radius + 0.5 * self.params.clearance_margin
        found = plan_manoeuvre(self.model, world, state, self.goal, keep, self.params.dt, floor=self.radius,
                               clear_within=clear_within, reach=max(1.0, self.params.goal_tolerance))
        if found is None or found.ticks == 0:
            self._manoeuvre, self._manoeuvre_retry_at = None, t + 5.0
            return False
        self.manoeuvres += 1
        self._manoeuvre, self._manoeuvre_tick, self._manoeuvre_held_since = found, 0, None
        self._escape, self._backup_until = None, -math.inf
        self.waypoint, self._committed, self._target, self._best_time = None, False, None, t
        self.mode = Mode.AVOIDING
        self.reason = f'manoeuvring: {found.arcs} arcs, {found.reversals} reversals'
        return True

    def drive_manoeuvre(self, state: FloatArray, t: float, dt: float, distance: float,
                        others: Sequence[OtherRobot]) -> FloatArray | None:
        """The manoeuvre's command for this tick, guarded; None once it is over (the usual loop takes over).

        The commands are replayed open loop while the robot is where the manoeuvre expects it; off by more
        than OFF_MANOEUVRE (a late command on a real graph) or held by the guard for 3 s (a robot in the
        way), it is planned again from where the robot is.
        """
        m = self._manoeuvre
        assert m is not None
        if self._manoeuvre_tick >= m.ticks:
            self._manoeuvre, self._manoeuvre_left_at = None, distance
            self._trap_distance, self._trap_time, self._best_time = distance, t, t
            return None
        expected = m.states[self._manoeuvre_tick]
        off = max(math.hypot(state[0] - expected[0], state[1] - expected[1]),
                  abs(wrap_angle(float(state[2]) - float(expected[2]))))
        held = self._manoeuvre_held_since is not None and t - self._manoeuvre_held_since >= 3 * HOLD_BEFORE_STEP
        if off > OFF_MANOEUVRE or held:
            self._manoeuvre_retry_at = -math.inf
            if not self.start_manoeuvre(state, t, others):
                self._manoeuvre = None
                return None
            m = self._manoeuvre
            assert m is not None
        command = m.commands[self._manoeuvre_tick]
        guarded = self.guard(state, command, dt, others)
        if guarded is command:
            self._manoeuvre_tick += 1
            self._manoeuvre_held_since = None
            self.mode, self.reason = Mode.AVOIDING, f'manoeuvring: {m.arcs} arcs, {m.reversals} reversals'
        elif self._manoeuvre_held_since is None:
            self._manoeuvre_held_since = t
        return guarded

    # ---------------------------------------------------- paths and traps
    def exact_path(self, position: FloatArray, others: Sequence[OtherRobot] = ()) -> OptimalPath | None:
        """The exact shortest path from position to the goal, or None when there is none.

        It keeps the planner's clearance (radius + margin) where it can, and less (down to the radius) when the
        one way through is narrower: a robot that fits through a gap has a path, even if its steps never go there.
        A start or goal already nearer an obstacle than the clearance lowers it to that distance. Other robots
        standing still (parked at their goals, most likely) are avoided like obstacles when a path round them
        exists; moving ones are left to the guard.
        """
        assert self.goal is not None
        world = self.parked_world(others)
        if world is not None:
            # The robot may already stand within a parked robot's inflation (it was held there): the path then
            # starts with what it has, down to almost nothing, and moves away.
            path = self._exact_path(world, position, floor=0.01)
            if path is not None:
                self.path_world = world
                return path
        self.path_world = self.world
        return self._exact_path(self.world, position)

    def parked_world(self, others: Sequence[OtherRobot]) -> World | None:
        """The world with the robots standing still (not at this robot's goal) as circles; None if none is.

        They are inflated by what the guard adds for another robot (a tick's travel and a quarter margin), so a
        way round a parked robot is not one the guard stops on.
        """
        assert self.goal is not None
        parked = [o for o in others if math.hypot(*o.velocity) < PARKED_SPEED
                  and math.hypot(o.position[0] - self.goal[0], o.position[1] - self.goal[1]) > o.radius + self.radius]
        if not parked:
            return None
        reach = self.params.max_speed * self.params.dt + 0.25 * self.params.clearance_margin + 0.01
        return World(self.world.workspace, self.world.obstacle_list + tuple(
            Circle((float(o.position[0]), float(o.position[1])), o.radius + reach) for o in parked))

    def _exact_path(self, world: World, position: FloatArray, floor: float | None = None) -> OptimalPath | None:
        assert self.goal is not None
        clearance = self.clearance
        if len(world.obstacles):
            ends = np.array([position, self.goal])
            clearance = min(clearance, float(world.obstacles.clearance(ends).min()) - 1e-9)
        path = None
        # Through a narrow gap the path keeps a quarter margin when it can (the guard stops at the radius
        # itself, so a path at exactly the radius would leave no slack for the controller).
        narrow = (min(clearance, self.radius + 0.25 * self.params.clearance_margin), min(clearance, self.radius))
        # A tractor-trailer cannot wrap tightly round a wall's end (it circles there): give it room to turn.
        wide = (clearance + TURN_ROOM,) if self.model.state_size == 4 else ()
        floor = self.radius - 1e-9 if floor is None else floor
        for keep in dict.fromkeys((*wide, clearance, *narrow)):
            if keep >= floor and keep > 0.0:
                path = shortest_path(world, position, self.goal, keep, spacing=PATH_SPACING)
                if path is not None:
                    break
        return path

    def no_path_reason(self, position: FloatArray) -> str:
        assert self.goal is not None
        return (f'no valid path: nothing keeps the robot radius {self.radius:g} m from the obstacles and the '
                f'border between ({position[0]:.3g}, {position[1]:.3g}) and the goal '
                f'({self.goal[0]:.3g}, {self.goal[1]:.3g})')

    def trapped(self, t: float, distance: float) -> bool:
        """Has the robot failed to come closer to the goal for trap_timeout seconds (outside an escape)?

        Near the goal the kinematic approach slows down (speed proportional to distance), so there half the
        distance counts as progress: a robot driving straight to its goal is never taken for trapped.
        """
        if not self.escapes_traps or self.params.trap_timeout <= 0 or self._escape is not None or \
                self._manoeuvre is not None:
            return False
        needed = min(self.params.progress_distance, 0.5 * self._trap_distance)
        if distance < self._trap_distance - needed or self._trap_distance == math.inf:
            self._trap_distance, self._trap_time = distance, t
            return False
        return t - self._trap_time > self.params.trap_timeout

    def start_escape(self, position: FloatArray, distance: float, t: float,
                     others: Sequence[OtherRobot] = ()) -> bool:
        """Leave a trap along the exact shortest path; False (and failed) if there is no path."""
        path = self.exact_path(position, others)
        if path is None:
            self.fail(self.no_path_reason(position))
            return False
        self.escapes += 1
        self._escape, self._escape_planned_at = EscapePath.from_path(path, self.path_world), t
        self._escape_best = math.inf
        self._escape_exit = min(distance, self._trap_distance) - self.params.progress_distance
        self.waypoint, self._committed, self._best_time = None, False, t
        self.mode, self.reason = Mode.AVOIDING, 'escaping a trap along the exact shortest path'
        return True

    def follow_escape(self, position: FloatArray, distance: float, t: float,
                      others: Sequence[OtherRobot]) -> FloatArray | None:
        """The escape target (planning/escape.py); None once the robot has left the trap (or failed).

        A step around another robot (the hold breaker) leaves the path; the path is replanned after it, and
        whenever no vertex ahead is in sight, at most every RETRY_AFTER seconds.
        """
        assert self._escape is not None and self.goal is not None
        if distance <= self._escape_exit:
            self._escape = None
            self._trap_distance, self._trap_time = distance, t
            return None
        if self._committed:
            if self.keep_waypoint(position, others):
                return self.waypoint
            self._committed = False
            if not self.replan_escape(position, t, others):
                return None
        target = self.escape_target(position, t, fresh=t - self._escape_planned_at < RETRY_AFTER)
        if target is None:
            if not self.replan_escape(position, t, others):
                return None
            target = self.escape_target(position, t, fresh=True)
        return target

    def replan_escape(self, position: FloatArray, t: float, others: Sequence[OtherRobot] = ()) -> bool:
        path = self.exact_path(position, others)
        if path is None:
            self.fail(self.no_path_reason(position))
            return False
        self._escape, self._escape_planned_at = EscapePath.from_path(path, self.path_world), t
        return True

    def escape_target(self, position: FloatArray, t: float, fresh: bool = False) -> FloatArray | None:
        assert self._escape is not None
        p = self.params
        target = self._escape.target(position, self.radius, p.clearance_margin, p.step_radius,
                                     p.waypoint_tolerance, self.clearance, fresh)
        if target is not None:
            # Progress on an escape is a shorter way left to go (path length), not a smaller distance to the goal.
            rest = self._escape.remaining(position)
            if rest < self._escape_best - p.progress_distance:
                self._escape_best, self._best_time = rest, t
            self.mode, self.reason = Mode.AVOIDING, 'escaping a trap along the exact shortest path'
        return target

    # --------------------------------------------------------------- checks
    def _robot_arrays(self, others: Sequence[OtherRobot]) -> tuple[FloatArray, FloatArray]:
        if not others:
            return np.zeros((0, 2)), np.zeros(0)
        centres = np.array([o.position for o in others], dtype=float)
        sums = np.array([o.radius for o in others], dtype=float) + self.radius
        return centres, sums

    def blocked(self, position: FloatArray, target: FloatArray, others: Sequence[OtherRobot],
                sensing_range: float | None = None) -> bool:
        """Does something within sensing range lie on the straight run to target? (eq. 11 + 'on the way')

        A run counts as clear if it keeps half the clearance margin beyond the radius: waypoints are placed
        a full margin away, so a robot that just reached one does not see the obstacle it skirts as blocking.
        """
        rng = self.params.sensing_range if sensing_range is None else sensing_range
        if self.robots_blocking(position, target, others, rng):
            return True
        # Static obstacles do not move: the answer is reused until the robot has travelled
        # detection_interval or the target changed (a detector running at a fixed travel rate).
        cached = self._detection
        if cached is not None and sensing_range is None and cached[1] is target and \
                math.hypot(position[0] - cached[0][0], position[1] - cached[0][1]) < self.params.detection_interval:
            return cached[2]
        within = self.radius + 0.5 * self.params.clearance_margin
        obstacles = self.world.obstacles
        blocked = False
        if len(obstacles):
            near = obstacles.distances(position) < rng
            blocked = bool(near.any() and (obstacles.path_distances(position, target)[near] < within).any())
        if sensing_range is None:
            self._detection = (position.copy(), target, blocked)
        return blocked

    def robots_blocking(self, position: FloatArray, target: FloatArray, others: Sequence[OtherRobot],
                        sensing_range: float, margin: float | None = None) -> bool:
        """Is another robot within sensing range and closer to the run than both radii plus `margin`?"""
        if not others:
            return False
        centres, sums = self._robot_arrays(others)
        margin = 0.5 * self.params.clearance_margin if margin is None else margin
        near = np.hypot(*(centres - position).T) - sums < sensing_range
        run = point_segment_distance(centres, position, target)
        return bool(np.any(near & (run < sums + margin)))

    def plan_next_step(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        """Run the swarm for one waypoint; None (and a status reason) when no feasible step exists."""
        assert self.goal is not None
        if self._last_t is not None and self._last_t < self._retry_at:
            return None
        centres, sums = self._robot_arrays(others)
        problem = StepProblem(self.world, position, self.goal, self.clearance, self.params.step_radius,
                              self.params.a, self.params.b, self.params.c, centres,
                              sums + self.params.clearance_margin)
        self.activations += 1
        # Robots met ahead are passed on the right when that is possible at all.
        offset = centres - position
        ahead = (np.hypot(*offset.T) - sums < self.params.sensing_range) & (offset @ (self.goal - position) > 0)
        step = None
        start = time.perf_counter()
        if ahead.any():
            problem.pass_on_right = offset[ahead]
            step = plan_step(problem, self.params, self.rng, self.step_method)
            problem.pass_on_right = np.zeros((0, 2))
        if step is None:
            step = plan_step(problem, self.params, self.rng, self.step_method)
        self.plan_time += time.perf_counter() - start
        if step is None:
            # Nothing feasible now; other robots may move away. Retry later rather than every tick.
            self._retry_at = (self._last_t or 0.0) + RETRY_AFTER
            self.mode, self.reason, self.waypoint, self.cost = Mode.AVOIDING, 'no valid step; waiting', None, 0.0
            return None
        self.mode, self.reason = Mode.AVOIDING, 'stepping around an obstacle'
        self.waypoint, self.cost = step.waypoint, step.cost
        self.plan.append(step.waypoint)
        return step.waypoint

    def keep_waypoint(self, position: FloatArray, others: Sequence[OtherRobot]) -> bool:
        """Follow the current waypoint unless it is reached or a robot has moved onto the run to it.

        "Onto the run" means closer than both radii: the step was planned to pass at least that far from
        every robot, possibly less than the full margin when the robots were already that close.
        """
        if self.waypoint is None:
            return False
        if math.hypot(self.waypoint[0] - position[0], self.waypoint[1] - position[1]) <= \
                self.params.waypoint_tolerance or \
                self.robots_blocking(position, self.waypoint, others, self.params.sensing_range, margin=0.0):
            self.waypoint = None
            return False
        return True

    def guard(self, state: FloatArray, command: FloatArray, dt: float,
              others: Sequence[OtherRobot]) -> FloatArray:
        """Stop instead of moving into an obstacle or within reach of another robot."""
        position = state[:2]
        # The plant integrates the command exactly as the model does (RK4 for a tractor-trailer); a straight
        # Euler guess cuts the corner of a tight turn and once let a robot end a tick 2.3 mm inside its radius.
        after = self.model.integrate(state, command, dt)[:2]
        obstacles = self.world.obstacles
        # Any point within (clearance - radius) of a point whose clearance is known is safe (triangle
        # inequality), so the obstacle distances are recomputed only when the robot leaves that disc.
        free = self._free_disc
        if len(obstacles) and (free is None or math.hypot(after[0] - free[0][0], after[1] - free[0][1]) >= free[1]):
            then = float(obstacles.clearance(after))
            if then < self.radius and then < float(obstacles.clearance(position)):
                self.reason = 'stopped: an obstacle is within the robot radius ahead'
                return np.zeros_like(command)
            self._free_disc = (after, then - self.radius)
        for other in others:
            centre = np.asarray(other.position, dtype=float)
            # The other robot may move up to `reach` before we see it again; a quarter of the clearance margin
            # more absorbs the delay of a real graph (odometry a tick old, a command a tick late).
            reach = (self.params.max_speed if self.params.max_speed > 0
                     else float(np.hypot(*other.velocity))) * dt + 0.25 * self.params.clearance_margin
            gap_now = float(np.hypot(*(position - centre)))
            gap_then = float(np.hypot(*(after - centre)))
            if gap_then < self.radius + other.radius + reach and gap_then < gap_now:
                self.reason = f'stopped: giving way to {other.name}'
                return np.zeros_like(command)
        return command


class FAStepKinematic(Navigator):
    """Kinematics to the goal; the Stepping Ahead Firefly swarm only when something blocks the way."""

    method = 'fastep'

    def choose_target(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        assert self.goal is not None
        following = self.keep_waypoint(position, others)
        self._committed = self._committed and following
        if self._committed:
            return self.waypoint
        if not self.blocked(position, self.goal, others):
            self.waypoint, self.cost, self.mode, self.reason = None, 0.0, Mode.KINEMATIC, 'way is clear'
            return self.goal
        if following:
            return self.waypoint
        return self.plan_next_step(position, others)


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


def make_navigator(algorithm: str, spec: RobotLike, radius: float, world: World, params: PlannerParams,
                   rng: np.random.Generator | int | None = None) -> Navigator:
    """A FAStep-Kinematic ('fastep') or ACO-Kinematic ('aco') navigator for a scenario robot."""
    from fastep_core.planning.optimal_kinematic import OptimalKinematic  # exact-path reference; imports this module
    classes = {'fastep': FAStepKinematic, 'aco': ACOKinematic, 'optimal': OptimalKinematic}
    if algorithm not in classes:
        raise ValueError(f'unknown algorithm {algorithm!r}; choose one of {", ".join(classes)}')
    model, controller = make_robot(spec, params)
    return classes[algorithm](model, controller, radius, world, params, rng)
