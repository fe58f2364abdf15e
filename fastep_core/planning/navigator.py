"""The per-robot decision loop every algorithm shares, and its safety nets.

A navigator is called once per control tick with the robot's state and the other robots it knows of, and
returns the command for the robot's kinematic model, in `fastep-sim` and in the ROS planner node alike. The
algorithms (planning/algorithms.py) differ only in `choose_target`: the point to drive to this tick. Around it
the behaviours of `tick`, in order of priority (planning/behaviours/), and on every command yielding to movers
and the guard (planning/safety/). When the swarm runs and the step it plans: planning/swarm/.
"""

from __future__ import annotations

import math
from typing import Callable, Protocol, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.errors import GoalError
from fastep_core.footprint import Footprint
from fastep_core.kinematics.model import Controller, RobotModel
from fastep_core.planning.behaviours import ROTATING, Behaviours, Tick, stand_clear
from fastep_core.planning.limits import Limits, saturating, with_limits
from fastep_core.planning.mode import Mode
from fastep_core.planning.others import OtherRobot, OtherRobots, robots_on_run
from fastep_core.planning.outline import inflated
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.recovery.back_up import SeenFree
from fastep_core.planning.recovery.manoeuvre_driver import ManoeuvreDriver
from fastep_core.planning.recovery.progress import ProgressChecker, TrapDetector
from fastep_core.planning.safety.base_response import BaseResponse, ShownResponse, all_finite, speed_of
from fastep_core.planning.safety.guard import Guard
from fastep_core.planning.safety.guard_inputs import GuardInputs
from fastep_core.planning.safety.yielding import Yield, Yielding
from fastep_core.planning.shortest_path.exact_path import NoPathHold, blocked_reason, no_path_reason, robot_path
from fastep_core.planning.shortest_path.optimal import OptimalPath
from fastep_core.planning.swarm import step_planning
from fastep_core.planning.swarm.detection import RunDetector
from fastep_core.world import World

__all__ = ['ROTATING', 'Mode', 'Navigator', 'OtherRobot', 'SpeedLaw']

FloatArray = NDArray[np.float64]


class SpeedLaw(Protocol):
    """A speed limit on the controller's commands that depends on where the robot is (FAStep-Route's RouteSpeed),
    within the limits it was made with (`under`: the same law within others)."""

    @property
    def limits(self) -> Limits: ...

    def under(self, limits: Limits, braking: float) -> SpeedLaw: ...

    def regulate(self, state: FloatArray, command: FloatArray, dt: float,
                 last: FloatArray | None = None) -> FloatArray: ...


class Navigator:
    """The loop every algorithm shares; subclasses decide the target of each tick (`choose_target`)."""

    method = 'fastep'        # the algorithm's name
    step_method = 'fastep'   # the optimizer that plans a step (plan_step's `method`)
    escapes_traps = True     # False for a navigator that already follows the exact path
    name = ''                # the robot's name as the other robots know it ('' unknown): ties at passages
    footprint: Footprint | None = None   # the robot's outline (take_footprint); None: it is its `radius` circle
    outline_extra = 0.0      # m the other robots are grown by: the circumscribed radius less `radius` (outline.py)

    def __init__(self, model: RobotModel, controller: Controller, radius: float, world: World,
                 params: PlannerParams | None = None, rng: np.random.Generator | int | None = None) -> None:
        self.model = model
        self.controller = controller
        self._applied: Callable[[FloatArray], None] | None = getattr(controller, 'applied', None)
        self.radius = float(radius)
        self.world = world
        self.params = p = params or PlannerParams()
        # The speed and acceleration limits and the control period: one value, handed whole to every part that
        # reads them (retune).
        self.limits: Limits = p.limits
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
        # What perception told the guards of the latest scan (take_perception): its margin, its returns and, where
        # planning runs in real time (planning/control.py), the free space recent scans saw, backing up only into it
        # (`seen`; None: the map alone, as in lock step).
        self.guard_inputs = GuardInputs()
        # The guard's stop brakes at this (m/s^2) where a control loop smooths the commands (planning/control.py):
        # the guard looks the braking distance further ahead. 0: a stop is immediate, as in lock step.
        self.braking = 0.0
        # What the base has shown it does (odometry against the commands): stops are planned no harder than that.
        # Fed by whoever sends the commands: `update` in lock step, the control loop's ControlTick otherwise.
        self.response = BaseResponse(bool(model.holonomic), self.limits.max_acceleration,
                                     self.limits.max_turn_acceleration)
        self.response_fed_elsewhere = False
        # Where the response is fed on another thread (the planner node's control tick): what it had measured when the
        # pass's snapshot was taken (take_response); None: the response itself is read.
        self.response_taken: ShownResponse | None = None
        self._last_command = np.zeros(2)   # the command `update` returned last
        # Whether the world is what the robot's laser shows (fastep_core/perception): a belief that can be wrong
        # for a moment, so no path in it holds the robot a while before the goal fails (fail_no_path).
        self.from_scans = False
        self.no_path = NoPathHold()
        self._speed = 0.0   # of the last command (m/s)
        self._measured_speed = 0.0   # of the base, as measured at the last tick (m/s)
        self._last_t: float | None = None
        self.committed = False                    # follow the waypoint to the end (a step that broke a hold)
        self._ticks = 0                           # control ticks so far
        self.steps = step_planning.StepPlanning()   # what step planning carries from tick to tick
        self.detector = RunDetector(self.radius)  # what lies on the run to the target, with its proofs
        self._stuck = 0                           # planned steps in a row that ended within waypoint_tolerance
        self.guard_check = Guard(model, self.radius, p, limits=self.limits)
        self.yielding = self._yielding(p)
        self.yield_kind = ''
        self.progress = ProgressChecker(p.progress_distance, p.progress_timeout)
        self.trap = TrapDetector(p.progress_distance, p.trap_timeout)
        # The tick's behaviours, each with its state (planning/behaviours/): arrival, the checks, the recoveries.
        self.behaviours = Behaviours(model, self.radius, p, self.limits)

    def take_footprint(self, footprint: Footprint, body_radius: float) -> None:
        """Plan for a robot with this outline: `radius` is then the planning circle (outline.planning_radius), the
        guard checks the polygon, and other robots are kept from `body_radius` (the circumscribed circle)."""
        self.footprint = footprint
        self.guard_check.footprint = footprint
        self.outline_extra = max(0.0, body_radius - self.radius)

    def take_perception(self, inputs: GuardInputs, world: World | None = None) -> None:
        """Perception's results for one scan: what the guards check against (one value, so the control loop never
        reads a margin of one scan with the returns of another) and, if given, the world now believed. The robot
        plans in what its laser shows from now on (`from_scans`)."""
        self.guard_check.obstacle_margin, self.guard_check.scan_points = inputs.obstacle_margin, inputs.scan_points
        self.guard_inputs = inputs
        self.from_scans = True
        if world is not None and world is not self.world:
            self.world = world

    def take_response(self, shown: ShownResponse) -> None:
        """What the base had measurably done when this pass's snapshot was taken (the control loop that measures it
        runs on another thread and goes on meanwhile): the pass plans its stops with it."""
        self.response_taken = shown

    @property
    def measured_base(self) -> BaseResponse | ShownResponse:
        """What a pass reads of the base's measured response: as taken with the snapshot (take_response), else the
        response itself (lock step and fastep-sim, where one thread measures and plans)."""
        taken = self.response_taken
        return self.response if taken is None else taken

    @property
    def seen(self) -> SeenFree | None:
        """The free space the recent scans saw, where the robot may back up (None: the map alone)."""
        return self.guard_inputs.seen

    @property
    def obstacle_margin(self) -> float:
        """What the guard keeps from obstacles beyond the robot's outline (perception's margin)."""
        return self.guard_check.obstacle_margin

    def _yielding(self, p: PlannerParams) -> Yielding:
        """Yielding with these parameters, the model and the limits as they are now."""
        return Yielding(self.model, self.radius, p.mover_horizon, 0.5 * p.clearance_margin, self.limits.max_speed,
                        self.limits.max_turn_rate)

    @property
    def clearance(self) -> float:
        """Distance a planned waypoint keeps from every obstacle surface."""
        return self.radius + self.params.clearance_margin

    @property
    def target(self) -> FloatArray | None:
        """The point the robot is driving to now: a waypoint or the goal."""
        return self._target

    def clear_target(self) -> None:
        """No target: the controller starts afresh at the next one (drive_to)."""
        self._target = None

    @property
    def failed(self) -> bool:
        return self.mode is Mode.FAILED

    @property
    def manoeuvring(self) -> ManoeuvreDriver | None:
        """A tractor-trailer's manoeuvres (None for a robot that turns in place)."""
        m = self.behaviours.manoeuvring
        return None if m is None else m.driver

    @property
    def manoeuvres(self) -> int:
        """Tractor-trailer manoeuvres found (replans included)."""
        m = self.manoeuvring
        return m.count if m is not None else 0

    @property
    def escaping(self) -> bool:
        """Is the robot following the exact path out of a trap?"""
        return self.behaviours.escaping.escape.active

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
        self.reference, self.committed = None, False
        self._stuck = 0
        self.behaviours.new_goal()
        self.steps.new_goal()
        self.no_path.reset()
        self.progress.reset(t)
        self.trap.reset(t)

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
        waited = self.no_path.waited(self._last_t or 0.0, self.params.blocked_timeout, self.from_scans)
        if waited is None:
            self.fail(no_path_reason(self.radius, position, self.goal, self.world if self.from_scans else None))
            return
        self.waypoint, self._target, self.cost = None, None, 0.0
        self.behaviours.path_check.checked = False
        self.reason = blocked_reason(self.world, position, self.goal, self.radius, waited, self.params.blocked_timeout)

    # ------------------------------------------------------- while running
    @classmethod
    def check_params(cls, params: PlannerParams) -> None:
        """Raise ParameterError (one line) when this algorithm cannot run with these parameters."""

    def retune(self, params: PlannerParams, controller: Controller | None = None) -> None:
        """Take new parameters while running (the ROS planner's dynamic parameters).

        Every part that reads them sees the new values from the next tick; the goal, the plan and the timers
        carry on. Their limits (`limits`) reach every reader in this one call: the model (`saturating`: the
        guards and the node's latency compensation predict with it), the guard, yielding, backing up, the base's
        response, FAStep-Route's speed law and the controller: `controller` (a new one: the gains are its own),
        or the one it has with the new limits. A new controller starts afresh at its first command, ramping from
        what the robot got. A control loop of this navigator takes them with ControlTick.retune. Raises
        ParameterError, changing nothing, when this navigator cannot run with them.
        """
        self.check_params(params)
        limits = params.limits
        if controller is None and limits != self.limits:
            controller = with_limits(self.controller, limits)
        elif controller is not None:
            controller = with_limits(controller, limits)
        self.params, self.limits = params, limits
        self.model = saturating(self.model, limits)
        self.steps.pending = None   # an unfinished step plan: planned afresh with the new values
        self.guard_check.model, self.guard_check.params, self.guard_check.limits = self.model, params, limits
        self.yielding = self._yielding(params)
        self.progress.distance, self.progress.timeout = params.progress_distance, params.progress_timeout
        self.trap.distance, self.trap.timeout = params.progress_distance, params.trap_timeout
        self.detector.forget()   # answers cached with the old sensing range and margin
        self.behaviours.retune(self.model, params, limits)
        self.response.retune(limits.max_acceleration, limits.max_turn_acceleration)
        if controller is not None and controller is not self.controller:
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
        self.progress.reset(t)
        self.trap.reset(t)
        self.behaviours.restart_clock(self.model, self.limits)
        self._target = None

    # ------------------------------------------------------------- the loop
    def update(self, t: float, state: FloatArray, others: Sequence[OtherRobot] = (),
               velocity: FloatArray | None = None, measured_at: float | None = None,
               pose: FloatArray | None = None) -> FloatArray:
        """One control tick: returns the command for the model (zeros when stopped). velocity: what the base
        measurably does now (odometry's twist, in the model's command form), measured at `measured_at` (its stamp;
        None: t); None: the last command returned. pose: the odometry's own pose then, in its frame (default: state),
        which shows a slide the twist does not (BaseResponse.slide).

        A controller with acceleration limits (diff_drive) is told the command the robot got, whatever chose it
        (the controller, the guard's stop, a recovery): its next command starts from there.
        """
        measured = self._last_command if velocity is None else np.asarray(velocity, dtype=float).reshape(2)
        if all_finite(measured) and all_finite(state):
            # A slide the wheels do not see shows in the poses (BaseResponse.slide); where a control loop measures,
            # the slide it found last.
            at = t if measured_at is None else measured_at
            measured = self.measured_base.corrected(measured) if self.response_fed_elsewhere else \
                self.response.slide(at, measured, state if pose is None else pose)
        # Other robots and movers grown to the circumscribed circle for a robot with a footprint (outline.py).
        others = inflated(others, self.outline_extra)
        command = self.tick(t, state, others, measured)
        # Standing still: every component 0 (NaN counts as moving, as for np.any; this runs every tick, where
        # np.any on two numbers cost as much as the guard's obstacle test).
        if not self.yield_kind and self.mode in (Mode.KINEMATIC, Mode.AVOIDING) and \
                not any(c != 0.0 for c in command.tolist()):
            command = self.stand_clear(state, others)
        if self._applied is not None:
            self._applied(command)
        self._speed = speed_of(command, self.model.holonomic)
        if not self.response_fed_elsewhere:
            self.response.observe(t, measured, command, measured_at)
        self._last_command = np.array(command, dtype=float)
        return command

    def stand_clear(self, state: FloatArray, others: Sequence[OtherRobot]) -> FloatArray:
        """A robot standing still that a mover would run into gets out of its way (behaviours.driving)."""
        return stand_clear(self, state, others)

    def tick(self, t: float, state: FloatArray, others: Sequence[OtherRobot] = (),
             velocity: FloatArray | None = None) -> FloatArray:
        """The command of one control tick (`update` without telling the controller): the first behaviour that
        answers (planning/behaviours/), in their order of priority. velocity: as measured (None: standing)."""
        self.yield_kind = ''   # what yielding to movers did this tick (planning/safety/yielding.py), '' for nothing
        self.driven = None
        self._ticks += 1
        dt = self.limits.dt if self._last_t is None or t <= self._last_t else t - self._last_t
        self._last_t = t
        if self.goal is None or self.mode in (Mode.ARRIVED, Mode.FAILED):
            return np.zeros(2)
        state = np.asarray(state, dtype=float)
        if not all_finite(state):
            self.reason = 'robot state is not finite; holding still'
            return np.zeros(2)
        position = state[:2]
        if not (isinstance(others, OtherRobots) and others.finite):
            others = [o for o in others if math.isfinite(o.position[0]) and math.isfinite(o.position[1])]
        measured = np.zeros(2) if velocity is None else velocity
        if not all_finite(measured):
            measured = self._last_command
        self._measured_speed = speed_of(measured, self.model.holonomic)
        now = Tick(self._ticks, t, dt, state, position, others,
                   math.hypot(self.goal[0] - position[0], self.goal[1] - position[1]), measured, self.goal,
                   self.goal_heading, self.world, self.measured_base, getattr(self.controller, 'last', None))
        return self.behaviours.command(self, now)

    def drive_to(self, state: FloatArray, target: FloatArray, t: float, dt: float,
                 others: Sequence[OtherRobot]) -> FloatArray:
        """The kinematic controller's command toward target, guarded; a robot kept stopped gets a recovery."""
        if target is not self._target:   # targets are never changed in place: identity tells a new one
            self.controller.reset(state, target)
            self._target = target
        command = self.regulate(state, self.controller.command(state, target, dt), dt)
        self.driven = target
        # Movers: slow down, wait or get out of the way over the time ahead (planning/safety/yielding.py).
        yielded = self.yield_to_movers(state, command, dt, others)
        self.yield_kind = yielded.kind
        if yielded.kind:
            command, self.reason = yielded.command, yielded.reason
        guarded = self.guard(state, command, dt, others)
        self.behaviours.backing_up.guarded(self, state, t, self.guard_check.stop, guarded is command, others)
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
        """planning/safety/yielding.py on this tick's command; a move out of a mover's way must pass the guard."""
        return self.yielding.check(state, command, others,
                                   lambda c: self.guard_check.check(self.world, state, c, dt, others) is c)

    def choose_target(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        """The algorithm: the point to drive to this tick (goal or waypoint), None to stand still."""
        raise NotImplementedError

    # --------------------------------------------------- detection and steps
    def blocked(self, position: FloatArray, target: FloatArray, others: Sequence[OtherRobot],
                sensing_range: float | None = None, horizon: float | None = None) -> bool:
        """Does something within sensing range lie on the straight run to target? (eq. 11 + 'on the way';
        planning/swarm/detection.py, RunDetector.blocked)"""
        return self.detector.blocked(self.world, self.params, position, target, others, sensing_range, horizon)

    def plan_next_step(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        """Run the swarm for one waypoint (eq. 3-10); None (and a status reason) when no feasible step exists or
        the step is finished on a later tick (planning/swarm/step_planning.py, plan_next_step)."""
        return step_planning.plan_next_step(self, position, others)

    def step_budget(self) -> int | None:
        """Swarm iterations this tick's step plan may run: params.step_iterations, None (to the end) for 0."""
        return self.params.step_iterations or None

    @property
    def step_pending_tick(self) -> int:
        """The tick whose step plan is still running (StepPlanning.pending_tick)."""
        return self.steps.pending_tick

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
        """Stop instead of moving into an obstacle or within reach of another robot (planning/safety/guard.py)."""
        braking = self.stop_deceleration()
        if braking > 0.0:   # its stops brake: look as far ahead as that takes, from the faster of command and base
            dt += 0.5 * max(self._speed, self._measured_speed) / braking
        guarded = self.guard_check.check(self.world, state, command, dt, others)
        if guarded is not command:
            self.reason = self.guard_check.reason
        return guarded

    def stop_deceleration(self) -> float:
        """What the guard's stop brakes at: `braking` (emergency_deceleration where a control loop smooths the
        commands, 0 for immediate in lock step), but no harder than the base has shown it can (BaseResponse)."""
        return self.measured_base.stop_within(self.braking)

    # --------------------------------------------------- paths and traps
    def exact_path(self, position: FloatArray, others: Sequence[OtherRobot] = ()) -> OptimalPath | None:
        """The exact shortest path to the goal round obstacles and parked robots (planning/shortest_path/exact_path.py);
        while blocked (fail_no_path), None without a search until the belief changes or BLOCKED_RETRY s have passed."""
        assert self.goal is not None
        t = self._last_t or 0.0
        if self.no_path.skip_search(self.world, t):
            return None
        path, self.path_world = robot_path(self.world, others, position, self.goal, self.radius, self.params,
                                           turn_room=not self.model.turns_in_place)
        self.no_path.searched(self.world, t, path is not None)
        return path

    def start_escape(self, position: FloatArray, distance: float, t: float,
                     others: Sequence[OtherRobot] = ()) -> bool:
        """Leave a trap along the exact shortest path (behaviours.Escaping); False (and failed) if there is none."""
        assert self.goal is not None
        return self.behaviours.escaping.start(self, self.world, position, distance, t, others)

    # ------------------------------------------------ recoveries
    def start_manoeuvre(self, state: FloatArray, t: float, others: Sequence[OtherRobot]) -> bool:
        """Search a manoeuvre round the obstacles and parked robots (behaviours.Manoeuvring); True if found."""
        m = self.behaviours.manoeuvring
        assert self.goal is not None and m is not None
        return m.start(self, self.world, self.goal, state, t, others)

    def drive_manoeuvre(self, state: FloatArray, t: float, dt: float, distance: float,
                        others: Sequence[OtherRobot]) -> FloatArray | None:
        """The manoeuvre's command for this tick, guarded; None once it is over (behaviours.Manoeuvring)."""
        m = self.behaviours.manoeuvring
        assert m is not None
        return m.drive(self, state, t, dt, distance, others)
