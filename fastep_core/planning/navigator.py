"""The per-robot decision loop every algorithm shares, and its safety nets.

A navigator is called once per control tick with the robot's state and the other robots it knows of, and
returns the command for the robot's kinematic model, in `fastep-sim` and in the ROS planner node alike. The
algorithms (planning/algorithms.py; FAStep-Kinematic, the paper's Algorithm 1, is planning/fastep_kinematic.py)
differ only in `choose_target`: the point to drive to this tick. Around it, in order: arrival, the goal's path
check (exact_path.py: 'no valid path' for a goal nothing reaches), the progress checker and trap detector
(progress.py), the way out of a trap (escape.py) or, for a robot that cannot turn in place, a manoeuvre
(manoeuvre_driver.py), backing up and the hold breaker when the guard keeps a robot stopped (recovery.py), and on
every command yielding to movers (yielding.py) and the guard (guard.py). A step's problem, swarm run and fitness
are step.py; detection of what lies on the way is detection.py.
"""

from __future__ import annotations

import math
import time
from enum import Enum
from typing import Callable, Protocol, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.errors import GoalError
from fastep_core.kinematics.model import Controller, RobotModel
from fastep_core.planning.detection import RunDetector
from fastep_core.planning.escape import ESCAPING, TrapEscape
from fastep_core.planning.exact_path import BLOCKED_RETRY, blocked_reason, no_path_reason, parked_world, robot_path
from fastep_core.planning.guard import Guard
from fastep_core.planning.manoeuvre_driver import ManoeuvreDriver
from fastep_core.planning.optimal import OptimalPath
from fastep_core.planning.others import OtherRobot, OtherRobots, robot_arrays, robots_on_run
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.progress import ProgressChecker, TrapDetector
from fastep_core.planning.recovery import (
    REVERSE_HORIZON,
    BackUp,
    SeenFree,
    StopTimer,
    backup_speed,
    free_room,
    reverse_free,
)
from fastep_core.planning.step import StepProblem, StepRun, step_run
from fastep_core.planning.step_planning import StepPlanning
from fastep_core.planning.yielding import Yield, Yielding
from fastep_core.world import World

__all__ = ['Mode', 'Navigator', 'OtherRobot', 'SpeedLaw']

FloatArray = NDArray[np.float64]
ROTATING = 'rotating to the goal heading'


class SpeedLaw(Protocol):
    """A speed limit on the controller's commands that depends on where the robot is (FAStep-Route's RouteSpeed)."""

    def regulate(self, state: FloatArray, command: FloatArray, dt: float,
                 last: FloatArray | None = None) -> FloatArray: ...


class Mode(str, Enum):
    """What a navigator is doing; the value is what the ROS status topic reports."""

    IDLE = 'idle'            # no goal yet
    KINEMATIC = 'kinematic'  # driving straight to the goal by the kinematic equations
    AVOIDING = 'avoiding'    # driving to a waypoint planned by the swarm (or escaping, manoeuvring)
    ARRIVED = 'arrived'
    FAILED = 'failed'


class Navigator:
    """The loop every algorithm shares; subclasses decide the target of each tick (`choose_target`)."""

    method = 'fastep'        # the algorithm's name
    step_method = 'fastep'   # the optimizer that plans a step (plan_step's `method`)
    escapes_traps = True     # False for a navigator that already follows the exact path
    name = ''                # the robot's name as the other robots know it ('' unknown): ties at passages

    def __init__(self, model: RobotModel, controller: Controller, radius: float, world: World,
                 params: PlannerParams | None = None, rng: np.random.Generator | int | None = None) -> None:
        self.model = model
        self.controller = controller
        self._applied: Callable[[FloatArray], None] | None = getattr(controller, 'applied', None)
        self.radius = float(radius)
        self.world = world
        self.params = p = params or PlannerParams()
        self.rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
        self.goal: FloatArray | None = None
        self.goal_heading: float | None = None    # the heading to end in (robots that turn in place), if any
        self.mode = Mode.IDLE
        self.reason = 'waiting for a goal'
        self.waypoint: FloatArray | None = None   # the swarm's waypoint being driven to
        self.plan: list[FloatArray] = []          # every waypoint planned for this goal
        self.cost = 0.0                           # fitness of the waypoint in use
        self.activations = 0                      # swarm runs
        self.plan_time = 0.0                      # wall seconds spent inside the step optimizer
        self.escapes = 0                          # trap escapes started
        self.reference: OptimalPath | None = None  # the exact shortest path, computed on the goal's first tick
        self.path_world = world                   # the world the last exact_path was planned in
        self._target: FloatArray | None = None    # what the controller steers to (identity tells a new one)
        self.driven: FloatArray | None = None     # the target this tick's command was driven to (drive_to), if any
        # The free space recent scans saw, given where planning runs in real time (planning/control.py): backing up
        # only into it. None: the map alone, as in lock step.
        self.seen: SeenFree | None = None
        # The guard's stop brakes at this (m/s^2) where a control loop smooths the commands (planning/control.py):
        # the guard looks the braking distance further ahead. 0: a stop is immediate, as in lock step.
        self.braking = 0.0
        # Whether the world is what the robot's laser shows (fastep_core/perception): a belief that can be wrong
        # for a moment, so no path in it holds the robot a while before the goal fails (fail_no_path).
        self.from_scans = False
        self._blocked_since: float | None = None   # since when no path was found in what the laser shows
        self._no_path_in: World | None = None      # the world the last search found no path in, and when
        self._no_path_at = -math.inf
        self._speed = 0.0   # of the last command (m/s)
        self._last_t: float | None = None
        self._path_checked = False                # has the goal been checked for a path
        self._committed = False                   # follow the waypoint to the end (a step that broke a hold)
        self._ticks = 0                           # control ticks so far
        self._hold_broken = -1                    # the tick whose hold breaker's plan could not keep right
        self.steps = StepPlanning()               # what step planning carries from tick to tick
        self.detector = RunDetector(self.radius)  # what lies on the run to the target, with its proofs
        self._stuck = 0                           # planned steps in a row that ended within waypoint_tolerance
        self.guard_check = Guard(model, self.radius, p)
        self.yielding = self._yielding(p)
        self.yield_kind = ''
        self.progress = ProgressChecker(p.progress_distance, p.progress_timeout)
        self.trap = TrapDetector(p.progress_distance, p.trap_timeout)
        self.escape = TrapEscape()
        self.stops = StopTimer()
        self.backup = BackUp(model, backup_speed(p))
        # A robot that cannot turn in place leaves traps and tight spots by manoeuvres of its own arcs.
        self.manoeuvring = None if model.turns_in_place else ManoeuvreDriver(model, self.radius, p)

    def _yielding(self, p: PlannerParams) -> Yielding:
        return Yielding(self.model, self.radius, p.mover_horizon, 0.5 * p.clearance_margin, p.max_speed,
                        p.max_turn_rate)

    @property
    def clearance(self) -> float:
        """Distance a planned waypoint keeps from every obstacle surface."""
        return self.radius + self.params.clearance_margin

    @property
    def target(self) -> FloatArray | None:
        """The point the robot is driving to now: a waypoint or the goal."""
        return self._target

    @property
    def failed(self) -> bool:
        return self.mode is Mode.FAILED

    @property
    def manoeuvres(self) -> int:
        """Tractor-trailer manoeuvres found (replans included)."""
        return self.manoeuvring.count if self.manoeuvring is not None else 0

    # ----------------------------------------------------------------- goals
    def set_goal(self, goal: Sequence[float], t: float = 0.0, heading: float | None = None) -> None:
        """Accept a new goal (raises GoalError if it is outside the map, occupied or not finite); `heading`: the
        one to end in, for a robot that turns in place (params.goal_heading), None for any."""
        self.world.check_point(goal, self.radius)
        if heading is not None and not math.isfinite(heading):
            raise GoalError(f'goal heading {heading} is not finite')
        self.goal = np.array([float(goal[0]), float(goal[1])])
        self.goal_heading = None if heading is None else math.atan2(math.sin(heading), math.cos(heading))
        self.mode, self.reason = Mode.KINEMATIC, 'goal accepted'
        self.waypoint, self.plan, self.cost, self._target = None, [], 0.0, None
        self.reference, self._path_checked, self._committed = None, False, False
        self._stuck, self._hold_broken = 0, -1
        self.steps.new_goal()
        self._blocked_since = self._no_path_in = None
        self.progress.reset(t)
        self.trap.reset(t)
        self.escape.stop()
        if self.manoeuvring is not None:
            self.manoeuvring.reset()

    def cancel(self, reason: str = 'goal canceled') -> None:
        """Drop the goal: idle, no target (the controller's caller brakes to a stop)."""
        self.goal, self.goal_heading = None, None
        self.mode, self.reason = Mode.IDLE, reason
        self.waypoint, self._target, self.cost = None, None, 0.0

    def fail(self, reason: str) -> None:
        self.mode, self.reason = Mode.FAILED, reason
        self.waypoint, self._target, self.cost = None, None, 0.0

    def fail_no_path(self, position: FloatArray) -> None:
        """No way to the goal in the world believed now: the goal fails, unless the robot plans in what its laser
        shows (`from_scans`) and has not been blocked for blocked_timeout yet; then it holds, says what blocks, and
        looks for a path again (exact_path: on each new belief, at least every BLOCKED_RETRY s)."""
        assert self.goal is not None
        t = self._last_t or 0.0
        since = t if self._blocked_since is None else self._blocked_since
        if not self.from_scans or self.params.blocked_timeout <= 0.0 or t - since >= self.params.blocked_timeout:
            self._blocked_since = None
            self.fail(no_path_reason(self.radius, position, self.goal))
            return
        self._blocked_since = since
        self.waypoint, self._target, self.cost, self._path_checked = None, None, 0.0, False
        self.reason = blocked_reason(self.world, position, self.goal, self.radius, t - since,
                                     self.params.blocked_timeout)

    # ------------------------------------------------------- while running
    @classmethod
    def check_params(cls, params: PlannerParams) -> None:
        """Raise ParameterError (one line) when this algorithm cannot run with these parameters."""

    def retune(self, params: PlannerParams, controller: Controller | None = None) -> None:
        """Take new parameters while running (the ROS planner's dynamic parameters).

        Every part that reads them sees the new values from the next tick; the goal, the plan and the timers
        carry on. A new controller (the gains are its own) starts afresh at its first command. Raises
        ParameterError, changing nothing, when this navigator cannot run with them.
        """
        self.check_params(params)
        self.params = params
        self.steps.pending = None   # an unfinished step plan: planned afresh with the new values
        self.guard_check.params = params
        self.yielding = self._yielding(params)
        if self.manoeuvring is not None:
            self.manoeuvring.params = params
        self.progress.distance, self.progress.timeout = params.progress_distance, params.progress_timeout
        self.trap.distance, self.trap.timeout = params.progress_distance, params.trap_timeout
        self.detector.forget()   # answers cached with the old sensing range and margin
        self.backup.speed = backup_speed(params)
        if controller is not None:
            # The new controller hears what the robot got, starting with what it does now: told nothing, a diff_drive
            # controller's ramp started from rest every tick (0.13 m/s at 20 Hz after any parameter change).
            applied = getattr(controller, 'applied', None)
            last = getattr(self.controller, 'last', None)
            if applied is not None and last is not None:
                applied(last)
            self.controller, self._applied = controller, applied
            self._target = None   # drive_to resets a controller when its target is new

    def restart_clock(self, t: float) -> None:
        """The clock was switched (wall <-> simulated time): every timer restarts at t; the goal stays.

        Times kept from the other clock would be read on this one: a jump of years ahead failed the progress
        checker and made the guard look a tick of that length ahead.
        """
        self._last_t = None
        self.steps.restart_clock()
        self._hold_broken = -1
        self.progress.reset(t)
        self.trap.reset(t)
        self.escape.stop()
        self.stops = StopTimer()
        self.backup = BackUp(self.model, backup_speed(self.params))
        if self.manoeuvring is not None:
            self.manoeuvring.reset()
        self._target = None

    # ------------------------------------------------------------- the loop
    def update(self, t: float, state: FloatArray, others: Sequence[OtherRobot] = ()) -> FloatArray:
        """One control tick: returns the command for the model (zeros when stopped).

        A controller with acceleration limits (diff_drive) is told the command the robot got, whatever chose it
        (the controller, the guard's stop, a recovery): its next command starts from there.
        """
        command = self.tick(t, state, others)
        # Standing still: every component 0 (NaN counts as moving, as for np.any; this runs every tick, where
        # np.any on two numbers cost as much as the guard's obstacle test).
        if not self.yield_kind and self.mode in (Mode.KINEMATIC, Mode.AVOIDING) and \
                not any(c != 0.0 for c in command.tolist()):
            command = self.stand_clear(state, others)
        if self._applied is not None:
            self._applied(command)
        self._speed = math.hypot(float(command[0]), float(command[1])) if self.model.holonomic else \
            abs(float(command[0]))
        return command

    def turn_to_heading(self, state: FloatArray, dt: float) -> FloatArray | None:
        """At the goal's position: the turn in place toward the goal's heading, within the turn rate and its
        acceleration from the last command; None when there is nothing to turn (no heading, a robot without one
        or that cannot turn in place, params.goal_heading 0, or facing it within yaw_goal_tolerance)."""
        p = self.params
        if self.goal_heading is None or not p.goal_heading or self.model.holonomic or \
                not self.model.turns_in_place or len(state) < 3:
            return None
        error = math.atan2(math.sin(self.goal_heading - state[2]), math.cos(self.goal_heading - state[2]))
        if abs(error) <= p.yaw_goal_tolerance:
            return None
        omega = p.turn_gain * error
        if p.max_turn_rate > 0.0:
            omega = max(-p.max_turn_rate, min(p.max_turn_rate, omega))
        last = getattr(self.controller, 'last', None)
        if last is not None and p.max_turn_acceleration > 0.0:
            step = p.max_turn_acceleration * dt
            omega = max(float(last[1]) - step, min(float(last[1]) + step, omega))
        return np.array([0.0, omega])

    def stand_clear(self, state: FloatArray, others: Sequence[OtherRobot]) -> FloatArray:
        """A robot standing still (no valid step, held, waiting) that a mover would run into gets out of its
        way (planning/yielding.py); zeros otherwise."""
        stop = np.zeros(2)
        state = np.asarray(state, dtype=float)
        if not np.isfinite(state).all():
            return stop
        yielded = self.yield_to_movers(state, stop, self.params.dt, others)
        if yielded.kind != 'evading':
            return stop
        self.yield_kind, self.reason = yielded.kind, yielded.reason
        return yielded.command

    def tick(self, t: float, state: FloatArray, others: Sequence[OtherRobot] = ()) -> FloatArray:
        """The command of one control tick (`update` without telling the controller)."""
        stop = np.zeros(2)
        self.yield_kind = ''   # what yielding to movers did this tick (planning/yielding.py), '' for nothing
        self.driven = None
        self._ticks += 1
        dt = self.params.dt if self._last_t is None or t <= self._last_t else t - self._last_t
        self._last_t = t
        if self.goal is None or self.mode in (Mode.ARRIVED, Mode.FAILED):
            return stop
        state = np.asarray(state, dtype=float)
        if not all(map(math.isfinite, state)):
            self.reason = 'robot state is not finite; holding still'
            return stop
        position = state[:2]
        if not (isinstance(others, OtherRobots) and others.finite):
            others = [o for o in others if math.isfinite(o.position[0]) and math.isfinite(o.position[1])]
        distance = math.hypot(self.goal[0] - position[0], self.goal[1] - position[1])
        if distance <= self.params.goal_tolerance:
            self.waypoint, self.cost, self._target = None, 0.0, None
            turn = self.turn_to_heading(state, dt)
            if turn is None:
                self.mode, self.reason = Mode.ARRIVED, 'goal reached'
                return stop
            self.mode, self.reason = Mode.KINEMATIC, ROTATING
            self.progress.made_progress(t)
            return self.guard(state, turn, dt, others)
        if not self._path_checked:
            self._path_checked = True
            self.reference = self.exact_path(position)
            if self.reference is None:
                self.fail_no_path(position)
                return stop
        if self.progress.stalled(t, distance):
            self.fail(self.progress.reason)
            return stop
        if self.trapped(t, distance):   # a robot that cannot turn in place manoeuvres out if it can
            if self.manoeuvring is not None and self.start_manoeuvre(state, t, others):
                self.escapes += 1
            elif not self.start_escape(position, distance, t, others):
                return stop
        if self.manoeuvring is not None and self.manoeuvring.active:
            command = self.drive_manoeuvre(state, t, dt, distance, others)
            if command is not None:
                return command
        if self.backup.active(t):
            return self.back_up(state, dt, others)
        if self.stops.hold_breaker_due(t) or self._hold_broken == self._ticks - 1:
            # The hold breaker comes once; a step of it that could not keep right is planned plainly next tick,
            # one that needs more swarm iterations than a tick has (params.step_iterations) goes on next tick.
            target = self.plan_next_step(position, others)
            self._committed = target is not None
            self._hold_broken = self._ticks if self.step_deferred else -1
        else:
            target = self.follow_escape(position, distance, t, others) if self.escape.active else None
            if self.failed:   # no way out of the trap
                return stop
            if not self.escape.active:
                target = self.choose_target(position, others)
        if target is None:
            if self.step_deferred and self._target is not None and \
                    not (self._hold_broken == self._ticks and self.steps.pending_tick == self._ticks):
                # The plain step is planned next tick; meanwhile the robot drives on as it did, guarded,
                # rather than stopping for one tick in the middle of a crowd. Not while the hold breaker's step
                # is still being planned: that would drive at what holds the robot, and the guard, stopping it
                # again, would call the hold breaker a second time.
                return self.drive_to(state, self._target, t, dt, others)
            self._target = None
            return stop
        return self.drive_to(state, target, t, dt, others)

    def drive_to(self, state: FloatArray, target: FloatArray, t: float, dt: float,
                 others: Sequence[OtherRobot]) -> FloatArray:
        """The kinematic controller's command toward target, guarded; a robot kept stopped gets a recovery."""
        if target is not self._target:   # targets are never changed in place: identity tells a new one
            self.controller.reset(state, target)
            self._target = target
        command = self.regulate(state, self.controller.command(state, target, dt), dt)
        self.driven = target
        # Movers: slow down, wait or get out of the way over the time ahead (planning/yielding.py).
        yielded = self.yield_to_movers(state, command, dt, others)
        self.yield_kind = yielded.kind
        if yielded.kind:
            command, self.reason = yielded.command, yielded.reason
        guarded = self.guard(state, command, dt, others)
        if guarded is command:
            self.stops.moved(state[:2])
            return guarded
        if self.stops.stopped(t, self.guard_check.stop, state[:2]):
            self._target = None   # the controller starts afresh after the recovery
            if not (self.manoeuvring is not None and self.start_manoeuvre(state, t, others)):
                self.backup.start(t)
        return guarded

    def regulate(self, state: FloatArray, command: FloatArray, dt: float) -> FloatArray:
        """The controller's command with the speed the way allows (`speed_law`: FAStep-Route's; the paper's
        controllers' command as it is)."""
        law = self.speed_law()
        return command if law is None else law.regulate(state, command, dt, getattr(self.controller, 'last', None))

    def speed_law(self) -> SpeedLaw | None:
        """What limits the controller's speed beyond its own law, frozen as it is now (the control loop uses it
        between passes: planning/control.py); None for the paper's controllers."""
        return None

    def yield_to_movers(self, state: FloatArray, command: FloatArray, dt: float,
                        others: Sequence[OtherRobot]) -> Yield:
        """planning/yielding.py on this tick's command; a move out of a mover's way must pass the guard."""
        return self.yielding.check(state, command, others,
                                   lambda c: self.guard_check.check(self.world, state, c, dt, others) is c)

    def choose_target(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        """The algorithm: the point to drive to this tick (goal or waypoint), None to stand still."""
        raise NotImplementedError

    # --------------------------------------------------- detection and steps
    def blocked(self, position: FloatArray, target: FloatArray, others: Sequence[OtherRobot],
                sensing_range: float | None = None, horizon: float | None = None) -> bool:
        """Does something within sensing range lie on the straight run to target? (eq. 11 + 'on the way';
        planning/detection.py, RunDetector.blocked)"""
        return self.detector.blocked(self.world, self.params, position, target, others, sensing_range, horizon)

    def plan_next_step(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        """Run the swarm for one waypoint (eq. 3-10); None (and a status reason) when no feasible step exists.

        With robots ahead the step first keeps right of them (planning/step.py, step_run). When that gives up, or
        the plan needs more swarm iterations than a tick has (params.step_iterations), the step is finished on the
        next tick (`step_deferred`; planning/step_planning.py), and `tick` drives on meanwhile.
        """
        assert self.goal is not None
        steps, tick = self.steps, self._ticks
        if steps.waiting(self._last_t):
            return None
        run, whole = steps.resumed(tick, self._last_t, self.world)
        if run is None:
            run = self.start_step(position, others)
        budget = steps.budget(tick, None if whole else self.step_budget(), self.params.step_iterations)
        start = time.perf_counter()
        done = run.advance(budget)
        self.plan_time += time.perf_counter() - start
        if not done:
            steps.unfinished(run, tick, self._last_t or 0.0)
            self.mode, self.reason = Mode.AVOIDING, 'planning a step (finished on the next tick)'
            return None
        step = run.plan
        if step is None and len(run.problem.pass_on_right):
            steps.rule_gave_up = tick
            self.mode, self.reason = Mode.AVOIDING, 'cannot keep right; planning the step without it'
            return None
        if step is None:
            # Nothing feasible now; other robots may move away. Retry later rather than every tick.
            steps.retry_later(self._last_t or 0.0)
            self.mode, self.reason, self.waypoint, self.cost = Mode.AVOIDING, 'no valid step; waiting', None, 0.0
            return None
        self.mode, self.reason = Mode.AVOIDING, 'stepping around an obstacle'
        self.waypoint, self.cost = step.waypoint, step.cost
        self.plan.append(step.waypoint)
        return step.waypoint

    def step_budget(self) -> int | None:
        """Swarm iterations this tick's step plan may run: params.step_iterations, None (to the end) for 0."""
        return self.params.step_iterations or None

    def start_step(self, position: FloatArray, others: Sequence[OtherRobot]) -> StepRun:
        """The step problem of this tick (eq. 10 toward step_target, the robots as they are and as yielding predicts
        them) and its swarm run, keeping right of the robots ahead unless the rule gave up last tick (then this
        plan continues that activation)."""
        plain = self.steps.plain(self._ticks)
        target = self.step_target()
        centres, sums = robot_arrays(others, self.radius)
        centres, sums = self.yielding.with_predictions(position, others, centres, sums,
                                                       self.params.step_radius / max(self.params.max_speed, 1e-6))
        problem = StepProblem(self.world, position, target, self.clearance, self.params.step_radius,
                              self.params.a, self.params.b, self.params.c, centres,
                              sums + self.params.clearance_margin)
        offset = centres - position
        ahead = (np.hypot(*offset.T) - sums < self.params.sensing_range) & (offset @ (target - position) > 0)
        if plain:
            ahead[:] = False
        else:
            self.activations += 1
        return step_run(problem, self.params, self.rng, self.step_method, offset[ahead])

    @property
    def step_deferred(self) -> bool:
        """This tick's step is not planned yet: it could not keep right of the robots ahead (the step without that
        rule comes next tick), or it needs more swarm iterations than a tick has (params.step_iterations)."""
        return self.steps.deferred(self._ticks)

    def step_target(self) -> FloatArray:
        """The point d in eq. 10 is measured to: the goal (FAStep-Route: the route vertex it aims at)."""
        assert self.goal is not None
        return self.goal

    def keep_waypoint(self, position: FloatArray, others: Sequence[OtherRobot]) -> bool:
        """Follow the current waypoint unless it is reached or a robot has moved onto the run to it.

        "Onto the run" means closer than both radii: the step was planned to pass at least that far from
        every robot, possibly less than the full margin when the robots were already that close.
        """
        if self.waypoint is None:
            return False
        if math.hypot(self.waypoint[0] - position[0], self.waypoint[1] - position[1]) <= \
                self.params.waypoint_tolerance or \
                robots_on_run(others, self.radius, position, self.waypoint, self.params.sensing_range, 0.0):
            self.waypoint = None
            return False
        return True

    def guard(self, state: FloatArray, command: FloatArray, dt: float,
              others: Sequence[OtherRobot]) -> FloatArray:
        """Stop instead of moving into an obstacle or within reach of another robot (planning/guard.py)."""
        if self.braking > 0.0:   # its stops brake (planning/control.py): look as far ahead as that takes
            dt += 0.5 * self._speed / self.braking
        guarded = self.guard_check.check(self.world, state, command, dt, others)
        if guarded is not command:
            self.reason = self.guard_check.reason
        return guarded

    # --------------------------------------------------- paths and traps
    def exact_path(self, position: FloatArray, others: Sequence[OtherRobot] = ()) -> OptimalPath | None:
        """The exact shortest path to the goal round obstacles and parked robots (planning/exact_path.py); while
        blocked (fail_no_path), None without a search until the belief changes or BLOCKED_RETRY s have passed."""
        assert self.goal is not None
        t = self._last_t or 0.0
        if self._blocked_since is not None and self._no_path_in is self.world and t - self._no_path_at < BLOCKED_RETRY:
            return None
        path, self.path_world = robot_path(self.world, others, position, self.goal, self.radius, self.params,
                                           turn_room=not self.model.turns_in_place)
        if path is None:
            self._no_path_in, self._no_path_at = self.world, t
        else:
            self._blocked_since = self._no_path_in = None
        return path

    def trapped(self, t: float, distance: float) -> bool:
        """Has the robot failed to come closer to the goal for trap_timeout seconds (outside an escape)?"""
        if not self.escapes_traps or self.escape.active or (self.manoeuvring is not None and self.manoeuvring.active):
            return False
        return self.trap.trapped(t, distance)

    def start_escape(self, position: FloatArray, distance: float, t: float,
                     others: Sequence[OtherRobot] = ()) -> bool:
        """Leave a trap along the exact shortest path (planning/escape.py); False (and failed) if there is none."""
        assert self.goal is not None
        path = self.exact_path(position, others)
        if path is None:
            self.fail_no_path(position)
            return False
        self.escapes += 1
        self.escape.start(path, self.path_world, t, min(distance, self.trap.best) - self.params.progress_distance,
                          self.world)
        self.waypoint, self._committed = None, False
        self.progress.made_progress(t)
        self.mode, self.reason = Mode.AVOIDING, ESCAPING
        return True

    def follow_escape(self, position: FloatArray, distance: float, t: float,
                      others: Sequence[OtherRobot]) -> FloatArray | None:
        """The escape's target; None once the robot has left the trap, or failed with no path left.

        A step around another robot (the hold breaker) leaves the path, which is planned again after it; so does a
        change of the world the robot knows (a sensed obstacle) that brings an obstacle within radius + a quarter
        margin of the rest of the path (the path was planned round what the robot knew then).
        """
        assert self.goal is not None
        if self.escape.left(distance):
            self.trap.reset(t, distance)
            return None
        replan = self._committed
        path = self.escape.path
        assert path is not None   # escaping
        if self.escape.known is not self.world:
            parked = parked_world(self.world, others, self.goal, self.radius, self.params) or self.world
            keep = min(path.keep, self.radius + 0.25 * self.params.clearance_margin) - 1e-6
            replan = not self.escape.adopt(self.world, parked, keep) or replan
        if self._committed:
            if self.keep_waypoint(position, others):
                return self.waypoint
            self._committed = False

        def plan() -> tuple[OptimalPath, World] | None:
            path = self.exact_path(position, others)
            return None if path is None else (path, self.path_world)

        target, progressed = self.escape.next_target(position, t, plan, self.radius, self.params, replan, self.world)
        if target is None:
            self.fail_no_path(position)
            return None
        if progressed:
            self.progress.made_progress(t)
        self.mode, self.reason = Mode.AVOIDING, ESCAPING
        return target

    # ------------------------------------------------ recoveries
    def start_manoeuvre(self, state: FloatArray, t: float, others: Sequence[OtherRobot]) -> bool:
        """Search a manoeuvre (planning/manoeuvre_driver.py) round the obstacles and parked robots; True if found."""
        assert self.goal is not None and self.manoeuvring is not None
        world = parked_world(self.world, others, self.goal, self.radius, self.params) or self.world
        if not self.manoeuvring.plan(world, state, self.goal, t):
            return False
        self.escape.stop()
        self.backup.stop()
        self.waypoint, self._committed, self._target = None, False, None
        self.progress.made_progress(t)
        self.mode, self.reason = Mode.AVOIDING, self.manoeuvring.status
        return True

    def drive_manoeuvre(self, state: FloatArray, t: float, dt: float, distance: float,
                        others: Sequence[OtherRobot]) -> FloatArray | None:
        """The manoeuvre's command for this tick, guarded; None once it is over (the usual loop takes over)."""
        m = self.manoeuvring
        assert m is not None
        command, ended = m.drive(state, t, distance, lambda c: self.guard(state, c, dt, others),
                                 lambda: self.start_manoeuvre(state, t, others))
        if ended:
            self.trap.reset(t, distance)
            self.progress.made_progress(t)
        elif command is not None and m.held_since is None:
            self.mode, self.reason = Mode.AVOIDING, m.status
        return command

    def back_up(self, state: FloatArray, dt: float, others: Sequence[OtherRobot]) -> FloatArray:
        """The backing-up recovery's command (planning/recovery.py), guarded; it ends where the guard stops it."""
        seen = self.seen
        free = None if seen is None else (
            lambda command: reverse_free(self.model, state, self.radius, command, REVERSE_HORIZON, self.world, seen,
                                         (), self.guard_check.obstacle_margin))
        guarded = self.backup.drive(state, dt, lambda points: free_room(self.world, points, others),
                                    lambda command: self.guard(state, command, dt, others), free)
        if self.backup.looking:
            self.reason = 'backing up: stuck; turning to see the space behind (no scan has seen it free)'
        elif self.backup.until > -math.inf:
            self.reason = 'backing up: stuck'
        return guarded
