"""fastep-planner: FAStep-Kinematic (or ACO-Kinematic, Optimal-Kinematic, DWA, FAStep-Route) planning and control
for one robot, the fastep_core Navigator on the live graph.

    fastep-planner --ros-args -r __ns:=/r1 -p algorithm:=fastep -p model:=point_mass -p robot_radius:=0.5

Every PlannerParams field (Table 1 of the paper and the rest) is a ROS parameter of the same name and default.
Odometry, goals, the world (/obstacles and /map, or /map alone with obstacle_source:=map), scans and the other robots
come in; cmd_vel, cost, waypoint, plan, status and /diagnostics go out. Planning runs on a thread of its own
(fastep_ros.planning_thread) and each control tick drives on its newest plan (fastep_core.planning.control), so the
control loop never waits for an exact path, a route or a swarm; a plan older than max_plan_age is not driven on.
Own odometry older than max_extrapolation is not acted on, because a command guarded at a position the robot has
left can drive it into an obstacle. In lock step (fastep_ros.lock_step) it acts once per odometry stamp instead.
It is a managed node in Nav2's order (fastep_ros.lifecycle): the constructor declares the parameters, configure
makes everything else from them, activate switches it on, deactivate stops the robot, cleanup releases it all.
Inputs, outputs, status values and timing: docs/guide.md, "The planner node", docs/real_time.md and
docs/reference/status.md; frames: docs/frames.md; other robots and goals: docs/robots_and_goals.md.
"""

from __future__ import annotations

import functools
import math
import time
import traceback
from typing import Any, Sequence, assert_never

import numpy as np
from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
from nav_msgs.msg import Path
from rclpy.clock import Clock, ClockType
from rclpy.lifecycle import LifecycleNode
from rclpy.parameter import Parameter
from rclpy.serialization import serialize_message
from std_msgs.msg import Float64

from fastep_core.errors import GoalError, ParameterError
from fastep_core.planning.algorithms import ALGORITHMS, NAVIGATORS, check_drives, make_navigator, make_robot
from fastep_core.planning.control import ControlTick, Plan
from fastep_core.planning.limits import LEAST_LIMIT, speed_limited
from fastep_core.planning.navigator import Mode, Navigator
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.params import PlannerParams
from fastep_core.scenario import MODELS
from fastep_core.world import World
from fastep_ros.behaviour_actions import behaviour_command, behaviour_plan
from fastep_ros.common import (
    RATE_RANGE,
    LatestLine,
    RepeatedLine,
    StartupError,
    check_range,
    declare_table,
    guard_clock,
    node_main,
    quiet_at_stop,
    shown,
    table_values,
)
from fastep_ros.costmap_services import forget_seen
from fastep_ros.goals import GoalSubscription
from fastep_ros.lifecycle import Lifecycle, transitions_to_member
from fastep_ros.limits import INLINE_WORLD_ITEMS, SPEED_LIMIT_LOG_PERIOD
from fastep_ros.live_tf import TfListener
from fastep_ros.lock_step import STAMP_EPS, LockStep
from fastep_ros.navigate_actions import NavigateActions
from fastep_ros.parameters import DynamicParameters
from fastep_ros.planner_inputs import Body, PlannerInputs
from fastep_ros.planner_params import PARAMETERS, TUNABLE, control_period, given_names, planner_params
from fastep_ros.planner_status import PlannerReports
from fastep_ros.planner_threads import (
    AdoptWorld,
    Change,
    DropGoal,
    FailGoal,
    ForgetSeen,
    Localized,
    PassResult,
    PlanSnapshot,
    RestartClock,
    Retune,
    TakeGoal,
)
from fastep_ros.planning_thread import PlanningThread
from fastep_ros.progress import Way
from fastep_ros.robots import RobotFollower, robot_name
from fastep_ros.sensors import declared_footprint
from fastep_ros.sim_time import SimTimeWatch
from fastep_ros.world_builder import build as build_world
from msg_tools import cdr, convert, frames, interface
from msg_tools.interface import RELIABLE, offered_qos

__all__ = ['PlannerNode', 'main']

DISCOVERY_PERIOD = 0.25  # wall seconds between looks at the graph for other robots ...
START_PERIOD = 0.05      # ... the first START_LOOKS looks (3 s) every START_PERIOD: a launcher waits for every
START_LOOKS = 60         # planner to see the others and its cmd_vel's readers (make demo's start waited 0.2-0.5 s)
HEARTBEAT = 1.0          # wall seconds between re-publications of status, waypoint and plan
PLANNING_JOIN = 5.0      # wall seconds cleanup waits at most for the planning pass under way to end


def same_heading(heading: float | str | None, kept: float | None) -> bool:
    """Is a goal's heading the one the navigator keeps (normalised into (-pi, pi], as set_goal keeps it)?"""
    if heading is None or kept is None or isinstance(heading, str):
        return heading is None and kept is None
    return math.atan2(math.sin(heading), math.cos(heading)) == kept


def stream_rng(seed: int, stream: int) -> np.random.Generator:
    """default_rng(seed) for stream -1, else the generator of SeedSequence(seed).spawn(stream + 1)[stream] (what
    fastep-sim gives its stream-th robot), built directly: spawn made every child before it, and stream 2e9 grew
    the planner by ~85 MB/s (a spawned child is SeedSequence(seed, spawn_key=(its index,)))."""
    if stream < 0:
        return np.random.default_rng(seed)
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(stream,)))


@transitions_to_member
class PlannerNode(LifecycleNode):
    """One robot's navigator (fastep_core) between its odometry and its cmd_vel. Its members: `inputs` (what it
    hears, fastep_ros.planner_inputs), `reports` (what it tells of itself, fastep_ros.planner_status), `lock` (lock
    step, fastep_ros.lock_step) and `lifecycle` (its transitions, fastep_ros.lifecycle); its parameters are
    fastep_ros.planner_params.PARAMETERS."""

    def __init__(self, node_name: str = 'planner', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        # Its transitions (fastep_ros.lifecycle): rclpy calls on_configure, on_activate, ..., handed to the member,
        # which calls configure, activate, deactivate and cleanup below, in Nav2's order.
        self.lifecycle = Lifecycle(self, self.configure, self.activate, self.deactivate, self.cleanup)
        self.clock_guard = guard_clock(self)   # a bad /clock message is ignored, never the end of the node
        # Declared once, here: a bad parameter (type, range) is a one-line exit 2 at start. Configure reads them.
        values = declare_table(self, PARAMETERS)
        self.unconfigured()
        self._made: frozenset[str] = frozenset()   # the attributes configure made: cleanup drops them
        self.lifecycle.start(values['autostart'])   # autostart: configured and active at once (fastep_ros.lifecycle)

    def unconfigured(self) -> None:
        """What the planner holds while unconfigured (before configure, after cleanup): nothing to drive with."""
        self.navigator: Navigator | None = None
        self.pending_goal: PoseStamped | None = None
        self.goal_msg: PoseStamped | None = None   # the message of the goal driven to (navigate_actions)
        self.goal: tuple[float, float] | None = None
        # Planning off the control path (fastep_ros.planning_thread), unless every tick plans (lock step, or asked).
        self.planning: PlanningThread[PlanSnapshot, PassResult] | None = None
        self.control_tick: ControlTick | None = None   # the control loop's part of the navigator, with the thread
        self.actions: NavigateActions | None = None    # Nav2's action servers, where nav2_msgs is

    # ------------------------------------------------------------------------------------------- lifecycle
    def configure(self) -> None:
        """Make everything from the parameters' values now (a value set while unconfigured included), as Nav2's
        on_configure does: the navigator's setting, the lifecycle publishers, the subscriptions, the planning
        thread, the timers (made off), the parameter callbacks and the action servers. A value the planner cannot
        run with is a StartupError (one line); what was made until then is released by cleanup."""
        before = frozenset(vars(self))
        try:
            values = table_values(self, PARAMETERS)
            self.read_parameters(values)
            self.fresh_state()
            self.make_outputs()
            self.make_inputs(values)
            self.make_control(values)
            self.make_services()
        finally:
            self._made = frozenset(vars(self)) - before

    def read_parameters(self, values: dict[str, Any]) -> None:
        """What the planner is built with: the parameters, checked; its body, random stream and inputs' setting."""
        try:
            self.params = planner_params(values, given_names(self))
        except ParameterError as exc:
            raise StartupError(str(exc)) from None
        if values['dt'] != self.params.dt:
            self.set_parameters([Parameter('dt', value=self.params.dt)])   # the dt parameter says the period
        self.algorithm, self.model, self.radius = values['algorithm'], values['model'], values['robot_radius']
        self.footprint = declared_footprint(values)   # the outline, where the robot is not a circle
        if self.footprint is not None:
            self.radius = self.footprint.radius
        length, trailer_length, hitch_offset = values['length'], values['trailer_length'], values['hitch_offset']
        self.seed, self.seed_stream = values['seed'], values['seed_stream']
        self.control_rate_hz, self.odom_timeout = values['control_rate_hz'], values['odom_timeout']
        stamped = values['use_stamped_cmd_vel']
        other_radius, other_timeout = values['other_robot_radius'], values['other_robot_timeout']
        if not other_timeout > 0.0:
            raise StartupError(f'parameter other_robot_timeout must be > 0, got {other_timeout:g}')
        self.max_extrapolation, self.frame_id = values['max_extrapolation'], values['frame_id']
        lock_step = values['lock_step']
        self.exclusive_cmd_vel = values['exclusive_cmd_vel']
        self.cmd_conflict = ''   # the other publishers on cmd_vel, while there are ('' when there are none)
        self.stop_on_failure = values['stop_on_failure']
        self.max_plan_age = values['max_plan_age']
        self.planning_timeout = values['planning_timeout']
        self._check(length, trailer_length, hitch_offset, other_radius, values['workspace'], values['obstacle_source'])
        self.lock_step = bool(lock_step)
        self.lock = LockStep()   # lock step's bookkeeping (fastep_ros.lock_step)
        self.body = Body(self.model, length, trailer_length, hitch_offset)
        self.stamped = stamped
        self.rng = stream_rng(self.seed, self.seed_stream)
        self.base_frame_id = frames.base_frame(self.get_namespace())
        # What it hears, and the robot's state made of it (fastep_ros.planner_inputs).
        self.inputs = PlannerInputs(self, values)

    def fresh_state(self) -> None:
        """What the planner decides, from nothing: a configure after a cleanup starts as the first did."""
        self.plan_problem = ''                         # why the plan is not driven on ('' when it is)
        # The goal failed on the executor for planning that left no plan for planning_timeout ('' when not), the
        # goal's message it failed (a goal taken after clears it), the newest pass result seen and since when.
        self.plan_failed, self._failed_goal = '', None
        self._result_seen: PassResult | None = None
        self._fresh_at = -math.inf
        self.control_count = 0                         # control ticks so far
        self._belief_shown: PassResult | None = None   # the pass whose belief tracked_obstacles shows
        self.fault_logged = False
        self.hold = ''  # why the robot is held still although it has a goal ('' when it is not)
        self.goal_refused = ''  # why the last goal was refused, while the goal before it is driven to ...
        self.refused_msg: PoseStamped | None = None   # ... and its message (an action's run knows its own by it)
        self.last_command = np.zeros(2)
        # Goals may come at any rate: their log lines at most once a second (fastep_ros.common.RepeatedLine). A
        # call site of its own for each severity: rclpy refuses two severities from one line of code.
        self.goal_info = RepeatedLine(lambda text: self.get_logger().info(text))
        self.goal_warning = RepeatedLine(lambda text: self.get_logger().warning(text))
        self._plan_key: tuple[Any, ...] | None = None
        self._target_key: tuple[float, ...] | None = None

    def make_outputs(self) -> None:
        """cmd_vel, waypoint, plan, cost and status: lifecycle publishers (LifecycleNode.on_activate switches them on,
        on_deactivate off), as /diagnostics' (make_services)."""
        self.cmd_pub = self.create_lifecycle_publisher(TwistStamped if self.stamped else Twist, interface.CMD_VEL,
                                                       offered_qos(interface.CMD_VEL))
        self.waypoint_pub = self.create_lifecycle_publisher(PoseStamped, interface.WAYPOINT,
                                                            offered_qos(interface.WAYPOINT))
        self.plan_pub = self.create_lifecycle_publisher(Path, interface.PLAN, offered_qos(interface.PLAN))
        self.cost_pub = self.create_lifecycle_publisher(Float64, interface.COST, offered_qos(interface.COST))
        self.reports = PlannerReports(self)   # status, /diagnostics, control timings (fastep_ros.planner_status)

    def make_inputs(self, values: dict[str, Any]) -> None:
        """The subscriptions: the robot's own inputs, goals, the other robots (and this one's footprint), TF, speed
        limits."""
        self.inputs.subscribe()
        # Goals from anyone (volatile, as RViz and `ros2 topic pub` send them) and from latched publishers
        # (fastep-launch: a planner restarted mid-run gets the goal it was driving to again): fastep_ros.goals.
        self.goal_sub = GoalSubscription(self, self.on_goal)
        # Announces this robot (its footprint) and follows the robots that announce themselves (fastep_ros.robots).
        other_radius, other_timeout = values['other_robot_radius'], values['other_robot_timeout']
        self.robots = RobotFollower(self, self.radius, other_radius, other_timeout, self.odom_timeout, self.now,
                                    lambda: self.reports.publish(force=True),
                                    on_odometry=self.lock_try if self.lock_step else None,
                                    outline=None if self.footprint is None else self.footprint.vertices)
        # Goals in other frames: resolved through /tf and /tf_static (fastep_ros.live_tf).
        self.tf = TfListener(self, dynamic=values['goal_frames_from_tf'] or self.inputs.map_to_odom_from_tf)
        # Nav2's speed limits (a speed filter, a fleet manager): the robot's max_speed capped by the newest.
        self.configured_max_speed = self.params.max_speed
        self.speed_limit: tuple[bool, float] = (False, 0.0)
        self.speed_limit_sub: Any = None
        # A limit may change with every message: its lines at most one a SPEED_LIMIT_LOG_PERIOD, the latest said.
        self.speed_limit_line = LatestLine(lambda text: self.get_logger().info(text), SPEED_LIMIT_LOG_PERIOD)
        try:
            from nav2_msgs.msg import SpeedLimit
            self.speed_limit_sub = self.create_subscription(SpeedLimit, interface.SPEED_LIMIT, self.on_speed_limit,
                                                            RELIABLE)
        except ImportError:
            pass   # no nav2_msgs: said once by navigate_actions

    def make_control(self, values: dict[str, Any]) -> None:
        """The planning thread (where passes run off the control path), the control and wall timers (off until
        activate), the watch on simulated time."""
        if values['planning_thread'] and (not self.lock_step or values['realtime']):
            self.planning = PlanningThread(self.plan_pass, self.get_logger().error)
        # Made off: activate switches them on, deactivate off again.
        self.control_timer = self.create_timer(1.0 / self.control_rate_hz, self.on_control_tick,
                                               autostart=False)
        steady = self.wall_clock = Clock(clock_type=ClockType.STEADY_TIME)
        self.wall_ticks = 0
        self.heartbeat_at = -math.inf   # steady seconds of the last re-publication
        self.wall_timer = self.create_timer(START_PERIOD, self.on_wall_tick, clock=steady, autostart=False)
        self.discover()
        self.update_world()
        self.sim_time = SimTimeWatch(self, self.clock_guard, values['clock_timeout'])
        self.clock_problem = ''   # why this node's time stands still ('' when it does not)

    def make_services(self) -> None:
        """/diagnostics, the parameter callbacks (tunable while configured) and Nav2's action servers."""
        self.reports.make_diagnostics()
        # Tunable while running (docs/parameters.md); the robot's body, the algorithm, the seed, the topics and
        # frames are what the node was built with and stay read-only.
        self.dynamic = DynamicParameters(self, TUNABLE, self.apply_parameters)
        self.get_logger().info(f'{self.algorithm} planner for a {self.model} of radius {self.radius:g} m, '
                               f'control at {self.control_rate_hz:g} Hz')
        # Nav2's navigate_to_pose, navigate_through_poses and follow_waypoints (fastep_ros.navigate_actions), where
        # nav2_msgs is: on the node <name>_navigation, spun on the action thread (fastep_ros.action_thread).
        self.actions = NavigateActions.make(self)

    def activate(self) -> None:
        """After LifecycleNode.on_activate has switched the publishers on: the navigator's timers restart (time
        spent inactive is no lack of progress), the timers on."""
        self.change(RestartClock(self.now()))   # time spent inactive is no lack of progress
        self._fresh_at = -math.inf              # nor of plans (planning_timeout counts afresh)
        self.control_timer.reset()
        self.wall_timer.reset()
        self.reports.changed()

    def deactivate(self) -> None:
        """Before LifecycleNode.on_deactivate switches the publishers off: the timers off, a zero cmd_vel (the
        robot stops), a navigation goal under way aborted, and status `inactive` sent."""
        self.control_timer.cancel()
        self.wall_timer.cancel()
        self.last_command = np.zeros(2)
        self.publish_command(self.last_command)
        if self.actions is not None:
            self.actions.check()   # not active: the run ends, aborted
        self.reports.changed()
        self.reports.publish(force=True)

    def cleanup(self, forget: bool = True) -> None:
        """Release everything configure made (Nav2's on_cleanup; also shutdown, an error, a configure that failed
        half-way, destroy_node): the planning thread stopped and joined, then the action thread (joined, its node
        and the action servers on it destroyed: NavigateActions.destroy), the parameter callbacks, the timers, the
        subscriptions and the publishers destroyed. `forget` (cleanup, an error, a failed configure): every
        attribute configure made dropped too, so the next configure builds afresh, with no goal, plan, world,
        perception, lock step or report of this run; otherwise (shutdown, destroy_node: nothing follows) what the
        run left is kept to be read."""
        made = vars(self)
        planning = self.planning
        if planning is not None:
            planning.stop(PLANNING_JOIN)
            if planning.alive:
                self.get_logger().warning(f'cleanup: the planning pass under way did not end within {PLANNING_JOIN:g} '
                                          's; it ends on its own, its plan unused')
        if self.actions is not None:
            self.actions.destroy()
        for member in ('dynamic', 'robots', 'tf', 'goal_sub', 'reports'):
            if member in made:
                made[member].destroy()
        if 'inputs' in made:
            self.inputs.unsubscribe()
        for name in ('control_timer', 'wall_timer'):
            if name in made:
                self.destroy_timer(made[name])
        if made.get('speed_limit_sub') is not None:
            self.destroy_subscription(made['speed_limit_sub'])
        for name in ('cmd_pub', 'waypoint_pub', 'plan_pub', 'cost_pub'):
            if name in made:
                self.destroy_lifecycle_publisher(made[name])
        if forget:
            for name in self._made:
                made.pop(name, None)
            self._made = frozenset()
            self.unconfigured()

    def update_world(self) -> None:
        """The world of the newest /obstacles and /map (PlannerInputs.world_job), once both have come: built at once
        when it is small (INLINE_WORLD_ITEMS) or every pass runs on the executor anyway (no planning thread), else
        on the world builder thread (fastep_ros.world_builder) while the control tick drives on the world before;
        then adopted (AdoptWorld) by PlannerInputs.take_built."""
        job = self.inputs.world_job()
        if job is None:
            return
        if self.planning is None or job.items(INLINE_WORLD_ITEMS) <= INLINE_WORLD_ITEMS:
            self.inputs.take_built(build_world(job))
        else:
            self.inputs.build_later(job)

    def change(self, request: Change) -> None:
        """Ask the planning side for a change (fastep_ros.planner_threads): applied between two passes on the
        planning thread, in the order asked, or at once without one."""
        if self.planning is None:
            self.apply(request)
        else:
            self.planning.call(functools.partial(self.apply, request))

    def apply(self, request: Change) -> None:
        """A change, on the planning side: the only writer of the navigator, perception and the goal driven to."""
        if isinstance(request, TakeGoal):
            self.take_goal(request.msg)
        elif isinstance(request, DropGoal):
            # In order with the goals before it: a goal given before the cancel never comes back after it.
            self.goal, self.goal_msg, self.pending_goal = None, None, None
            if self.navigator is not None:
                self.navigator.cancel(request.reason)
            if self.planning is not None:
                self.planning.drop_plan()
        elif isinstance(request, FailGoal):
            if self.navigator is not None:
                self.navigator.fail(request.reason)
        elif isinstance(request, AdoptWorld):
            self.adopt_world(request.world, request.count)
        elif isinstance(request, Retune):
            nav = self.navigator
            if nav is not None:
                nav.retune(request.params, make_robot(self.body, request.params)[1])
                if self.planning is not None:
                    self.control_tick = ControlTick(nav, self.inputs.scans.timeout)
        elif isinstance(request, Localized):
            self.inputs.scan_perception.localized(None if request.covariance is None else list(request.covariance),
                                                  request.sigmas)
        elif isinstance(request, RestartClock):
            if self.navigator is not None:
                self.navigator.restart_clock(request.t)
            if self.planning is not None:
                self.planning.drop_plan()   # planned before the pause, or on the other clock: not driven on
        elif isinstance(request, ForgetSeen):   # a costmap-clearing service (fastep_ros.costmap_services)
            request.done(forget_seen(self.inputs.scan_perception.perception, self.navigator, request.centre,
                                     request.side, request.inside))
        else:
            assert_never(request)

    def adopt_world(self, world: World, count: int) -> None:
        """AdoptWorld: the first world makes the navigator (and its control tick), a later one replaces its map."""
        self.inputs.world = world   # the map perception fuses scans with: the planning side's, as the navigator
        self.inputs.scan_perception.reset()   # a new map: what the scans showed is believed afresh on it
        if self.navigator is None:
            self.navigator = nav = make_navigator(self.algorithm, self.body, self.radius, world, self.params,
                                                  self.rng, footprint=self.footprint)
            nav.name = robot_name(self.get_namespace())   # as the other robots' planners name it
            if self.planning is not None:
                self.planning.drop_plan()
                self.control_tick = ControlTick(nav, self.inputs.scans.timeout)
            self.get_logger().info(f'world known: {count} obstacles in {world.workspace}')
        else:
            self.navigator.world = world
            self.inputs.world_info(f'world updated: {count} obstacles')   # at most one line a WORLD_LOG_PERIOD
        self.reports.changed()   # the obstacle count is part of the status
        if self.pending_goal is not None:
            goal, self.pending_goal = self.pending_goal, None
            self.on_goal(goal)
        self.reports.publish()

    # ------------------------------------------------------------------------------------------- setup
    def _check(self, length: float, trailer_length: float, hitch_offset: float, other_radius: float,
               workspace: list[float], obstacle_source: str) -> None:
        if self.algorithm not in ALGORITHMS:
            raise StartupError(f'parameter algorithm must be one of {", ".join(ALGORITHMS)}, '
                               f'got {self.algorithm!r}')
        if self.model not in MODELS:
            raise StartupError(f'parameter model must be one of {", ".join(MODELS)}, got {self.model!r}')
        try:
            check_drives(self.algorithm, self.model)
        except ParameterError as exc:
            raise StartupError(f'parameter algorithm: {exc}') from None
        check_range('control_rate_hz', self.control_rate_hz, *RATE_RANGE, ' Hz')
        for name, value in (('robot_radius', self.radius), ('odom_timeout', self.odom_timeout), ('length', length),
                            ('trailer_length', trailer_length)):
            if value <= 0.0:
                raise StartupError(f'parameter {name} must be > 0, got {value:g}')
        if self.seed < 0 or self.seed_stream < -1:
            raise StartupError(f'parameter seed must be >= 0 and seed_stream >= -1, got {self.seed} and '
                               f'{self.seed_stream}')
        if obstacle_source not in ('markers', 'map'):
            raise StartupError(f'parameter obstacle_source must be markers or map, got {obstacle_source!r}')
        if hitch_offset < 0.0 or other_radius < 0.0 or self.max_extrapolation < 0.0:
            raise StartupError('parameters hitch_offset, other_robot_radius and max_extrapolation must be >= 0')
        if workspace and (len(workspace) != 4 or not (workspace[0] < workspace[2] and workspace[1] < workspace[3])):
            raise StartupError(f'parameter workspace must be [xmin, ymin, xmax, ymax] with min < max, got {workspace}')

    def apply_parameters(self, changes: dict[str, Any]) -> str:
        """DynamicParameters' apply: check every change, then apply them all to the running node; why not if not.
        The planner's dt follows control_rate_hz (planner_params.control_period): a dt set that disagrees with it is
        refused; a new rate alone gives dt its new period, and the dt parameter is set to it."""
        planner = {name: value for name, value in changes.items() if name in PlannerParams.names()}
        params = self.params
        if 'dt' in changes or 'control_rate_hz' in changes:
            try:
                period = control_period(changes.get('control_rate_hz', self.control_rate_hz), changes.get('dt'),
                                        self.params.dt)
            except ParameterError as exc:
                return str(exc)
            planner.pop('dt', None)
            if 'dt' in changes or period != self.params.dt:
                planner['dt'] = period
        if planner:
            try:
                params = self.params.with_overrides(planner)
                NAVIGATORS[self.algorithm].check_params(params)
            except ParameterError as exc:
                return str(exc)
        odom_timeout = changes.get('odom_timeout', self.odom_timeout)
        if odom_timeout <= 0.0:
            return f'parameter odom_timeout must be > 0, got {odom_timeout:g}'
        if planner:
            if 'max_speed' in planner:   # what the speed limit (speed_limit topic) is taken of
                self.configured_max_speed = params.max_speed
                params = params.with_overrides({'max_speed': self.limited_speed()})
            if params != self.params or set(planner) != {'dt'}:   # the dt parameter set to the period it has: no change
                self.retune(params)
        self.odom_timeout = odom_timeout
        self.max_extrapolation = changes.get('max_extrapolation', self.max_extrapolation)
        self.max_plan_age = changes.get('max_plan_age', self.max_plan_age)
        self.planning_timeout = changes.get('planning_timeout', self.planning_timeout)
        self.exclusive_cmd_vel = changes.get('exclusive_cmd_vel', self.exclusive_cmd_vel)
        self.stop_on_failure = changes.get('stop_on_failure', self.stop_on_failure)
        self.robots.fleet.still_after = self.odom_timeout
        self.robots.override_radius = changes.get('other_robot_radius', self.robots.override_radius)
        if 'control_rate_hz' in changes:
            self.control_rate_hz = changes['control_rate_hz']
            self.control_timer.timer_period_ns = int(round(1e9 / self.control_rate_hz))
            if 'dt' not in changes and self.get_parameter('dt').value != self.params.dt:
                self.set_parameters([Parameter('dt', value=self.params.dt)])   # the dt parameter says the period
        self.sim_time.timeout = changes.get('clock_timeout', self.sim_time.timeout)
        scans = self.inputs.scans
        scans.timeout, scans.tolerance = changes.get('scan_timeout', scans.timeout), \
            changes.get('transform_tolerance', scans.tolerance)
        self.reports.changed()
        return ''

    def retune(self, params: PlannerParams) -> None:
        """Hand new planner parameters to the navigator between two planning passes, in one change: its limits reach
        the model (which the latency compensation predicts with), the guards, the controller, the route's speed law
        and, in the control tick rebuilt with them, the velocity smoother, from the next control tick on."""
        self.change(Retune(params))
        self.params = params

    def on_speed_limit(self, msg: Any) -> None:
        """nav2_msgs/SpeedLimit, as Nav2's controller server takes it from its speed filter: a percentage of
        max_speed, or m/s; 0 lifts it. The robot's max_speed (the parameter, unchanged) is capped by it, a positive
        limit always at a positive cap (at least LEAST_LIMIT: limits.speed_limited), in force at once, on status
        (`speed_limit`) and in the log at most once a SPEED_LIMIT_LOG_PERIOD (the latest change)."""
        percentage, value = bool(msg.percentage), float(msg.speed_limit)
        given = f'{value:g}{" %" if percentage else " m/s"}'
        if not (math.isfinite(value) and value >= 0.0 and (value <= 100.0 or not percentage)):
            self.get_logger().warning(f'ignoring speed_limit {given}: a limit is a finite number >= 0 (a percentage '
                                      f'at most 100)', throttle_duration_sec=5.0)
            return
        if percentage and value > 0.0 and self.configured_max_speed <= 0.0:
            self.get_logger().warning(f'speed_limit {given} caps nothing: max_speed is 0 (unlimited), and a '
                                      f'percentage of it is no speed; send the limit in m/s', throttle_duration_sec=5.0)
        speed = self.limited_speed((percentage, value))
        if speed != self.params.max_speed:
            try:
                params = self.params.with_overrides({'max_speed': speed})
                NAVIGATORS[self.algorithm].check_params(params)
            except ParameterError as exc:   # none known: every positive limit is a cap the navigators take
                self.get_logger().warning(f'ignoring speed_limit {given}: {exc}', throttle_duration_sec=5.0)
                return
            self.retune(params)
            configured = self.configured_max_speed
            asked = configured * (value / 100.0) if percentage else value   # 0 when it underflows
            least = '' if asked >= LEAST_LIMIT else \
                f' (the least cap: {given}{f" of {configured:g} m/s" if percentage else ""} is less)'
            self.speed_limit_line(f'speed limit: max_speed {speed:g} m/s{least}' if value > 0.0 else
                                  f'speed limit lifted: max_speed {speed:g} m/s')
        if (percentage, value) != self.speed_limit:
            self.reports.changed()   # the cap is on status
        self.speed_limit = (percentage, value)

    def limited_speed(self, limit: tuple[bool, float] | None = None) -> float:
        """max_speed as configured, capped by the speed limit kept or `limit` ((percentage, value); 0: unlimited, as
        max_speed 0 means): a positive limit at a positive cap (limits.speed_limited)."""
        percentage, value = self.speed_limit if limit is None else limit
        return speed_limited(self.configured_max_speed, value, percentage)

    def speed_cap(self) -> float | None:
        """The cap (m/s) the speed limit kept puts on max_speed, as status' `speed_limit` says it; None without
        one (none, lifted, or a percentage of an unlimited max_speed)."""
        percentage, value = self.speed_limit
        if value <= 0.0 or (percentage and self.configured_max_speed <= 0.0):
            return None
        return self.limited_speed()

    # ------------------------------------------------------------------------------------------- helpers
    @property
    def ros(self) -> LifecycleNode:
        """The node as rclpy sees it: what the members create their subscriptions and publishers on."""
        return self

    def now(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    def locked(self) -> bool:
        """Lock step is on: asked for, and the node runs on simulated time."""
        return self.lock_step and self.sim_time.active

    def stamp(self) -> Any:
        return self.get_clock().now().to_msg()

    def stamp_parts(self) -> tuple[int, int]:
        """(sec, nanosec) of stamp(), for the writers of msg_tools.cdr."""
        ns = self.get_clock().now().nanoseconds
        return ns // 1_000_000_000, ns % 1_000_000_000

    def on_goal(self, msg: PoseStamped) -> None:
        resolved, _ = self.goal_in_map(msg)   # in a frame TF does not resolve: refused by take_goal, saying so
        self.change(TakeGoal(resolved))

    def goal_in_map(self, msg: PoseStamped) -> tuple[PoseStamped, str]:
        """The goal in the map frame: as it is when given there; from any other frame /tf and /tf_static resolve
        (odom, base_link, another robot's frame), moved with its heading; (msg, why not) when none does."""
        frame = msg.header.frame_id.lstrip('/')
        if frame in ('', 'map', self.frame_id):
            return msg, ''
        pose = self.tf.lookup(self.frame_id, frame)
        if pose is None:
            return msg, f'goal frame {shown(frame)}: no transform to {self.frame_id!r} on /tf or /tf_static'
        q = msg.pose.orientation
        has_heading = q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w > 0.0
        local = (msg.pose.position.x, msg.pose.position.y, convert.yaw_of(q.x, q.y, q.z, q.w) if has_heading else 0.0)
        x, y, yaw = frames.compose(pose, local)
        out = PoseStamped()
        out.header.stamp, out.header.frame_id = msg.header.stamp, self.frame_id
        out.pose.position.x, out.pose.position.y = x, y
        if has_heading:
            out.pose.orientation.z, out.pose.orientation.w = math.sin(0.5 * yaw), math.cos(0.5 * yaw)
        else:
            out.pose.orientation.w = 0.0   # a quaternion of zero length: no heading asked for, as given
        return out, ''

    def take_goal(self, msg: PoseStamped) -> None:
        """A goal, given to the navigator (on the planning thread when there is one)."""
        point = convert.pose_stamped_to_point(msg)
        heading = self.goal_heading_of(msg)
        if self.navigator is None:
            self.pending_goal = msg
            self.goal_info(f'goal ({point[0]:g}, {point[1]:g}) received; waiting for the world')
            self.reports.publish()
            return
        nav = self.navigator
        if self.goal is not None and nav.mode in (Mode.KINEMATIC, Mode.AVOIDING) and \
                tuple(float(v) for v in point) == self.goal and same_heading(heading, nav.goal_heading):
            self.goal_msg = msg   # the goal driven to already (a latched goal seen twice, or sent again)
            return
        try:
            problem = self.goal_problem(msg)
            if problem:
                raise GoalError(problem)
            self.navigator.set_goal(point, self.now(), None if isinstance(heading, str) else heading)
        except GoalError as exc:
            self.goal_refused, self.refused_msg = f'goal ({point[0]:g}, {point[1]:g}) refused: {exc}', msg
            self.goal_warning(self.goal_refused)
            if self.goal is None or nav.mode not in (Mode.KINEMATIC, Mode.AVOIDING):
                self.goal = None
                nav.fail(f'goal refused: {exc}')
            # else the goal under way stays: a bad goal must not stop a robot driving to a good one
        else:
            self.goal_refused, self.refused_msg = '', None
            self.goal = (float(point[0]), float(point[1]))
            self.goal_msg = msg
            if self.planning is not None:
                self.planning.drop_plan()   # no more driving toward the last goal's target: brake until the new plan
            self.goal_info(f'new goal ({point[0]:g}, {point[1]:g})')
        self.publish_plan(force=True)
        self.reports.publish()

    def goal_problem(self, msg: PoseStamped) -> str:
        """Why a goal cannot be driven to ('' when it can, as far as the world known now says): its frame, an
        occupied cell of /map, a heading that is not finite, a point outside the map, inside an obstacle or not
        finite."""
        point = convert.pose_stamped_to_point(msg)
        frame = msg.header.frame_id
        heading = self.goal_heading_of(msg)
        if frame.lstrip('/') not in ('', 'map', self.frame_id):
            return self.goal_in_map(msg)[1] or f'goal frame {shown(frame)}: resolve it with goal_in_map first'
        if isinstance(heading, str):
            return heading
        nav = self.navigator
        try:
            if nav is not None:
                nav.world.check_point(point, nav.radius)
        except GoalError as exc:
            return str(exc)
        if self.inputs.occupied is not None and self.inputs.occupied(point):
            # Inside an occupied region of /map, far from its outline: the walls alone would not say so.
            return f'goal ({point[0]:g}, {point[1]:g}) is occupied: an occupied cell of /map'
        return ''

    def drop_goal(self, reason: str) -> None:
        """Forget the goal (a cancel): the robot brakes to a stop within its limits, status idle with `reason`."""
        self.change(DropGoal(reason))

    def goal_heading_of(self, msg: PoseStamped) -> float | str | None:
        """The heading a goal asks a robot that turns in place to end in (its orientation's yaw; None for other
        models and for a quaternion of zero length, which says none); why not, as text, when it is not finite."""
        if self.model != 'diff_drive':
            return None
        q = msg.pose.orientation
        try:
            return convert.yaw_of(q.x, q.y, q.z, q.w)
        except ValueError as exc:
            return None if 'zero length' in str(exc) else f'goal orientation: {exc}'

    def discover(self) -> bool:
        """Look at the graph for robots that announce themselves (fastep_ros.robots); True if those followed
        changed."""
        return self.robots.discover()

    def take_others(self) -> None:
        """The newest odometry of every other robot followed (fastep_ros.robots takes it when it is used)."""
        self.robots.take()

    def destroy_node(self) -> None:
        # What configure made (cleanup: the planning thread joined first), if anything; its values stay to be read.
        self.lifecycle.release(forget=False)
        super().destroy_node()

    # ------------------------------------------------------------------------------------------- lock step
    @quiet_at_stop
    def lock_try(self) -> None:
        """Lock step: act on the newest own odometry stamp once every input of its time is in (fastep_ros.lock_step).
        Called whenever one of them comes, on the control timer, and on the wall timer (inputs given up on)."""
        if not self.locked() or self.inputs.odom is None or not self.lifecycle.is_active:
            return
        stamp, lock = self.inputs.odom_stamp, self.lock
        if stamp <= lock.acted + STAMP_EPS:
            return   # acted on already (most calls: the other robots' odometry of the tick), no clock read
        now = self.now()
        if not lock.due(stamp, now):
            return
        fleet = self.robots.fleet
        # The steady clock's seconds (CLOCK_MONOTONIC, as the wall clock's), read without building a Time.
        wall = time.monotonic()
        blocker = lock.blocker   # the robot waited for at the last look: while it is behind, nothing else counts
        if blocker is not None and lock.held(blocker.stamp if fleet.is_fresh(blocker, now) else None, stamp, wall):
            return
        fresh = fleet.fresh(now)
        inputs = {robot.name: robot.stamp for robot in fresh}
        if self.model == 'tractor_trailer':
            inputs['trailer_pose'] = self.inputs.trailer_stamp   # the state of its time is odometry and trailer pose
        self.inputs.retry_scans(now)
        scan_sub = self.inputs.scan_sub
        if scan_sub is not None and scan_sub.get_publisher_count() > 0:
            inputs['scan'] = -math.inf if self.inputs.pending_scan is None else self.inputs.pending_scan.stamp
        late = lock.late(stamp, inputs, wall)
        if late:
            # held() looks at a robot's stamp alone, and only without scans (their retry runs here).
            lock.blocker = next((r for r in fresh if r.name == late[0]), None) if scan_sub is None else None
            return
        if lock.abandoned:
            self.get_logger().warning(f'lock step: nothing stamped {stamp:g} s from {", ".join(lock.abandoned)} '
                                      f'after {lock.wait:g} s of wall time; acting without (until it comes again)')
        lock.acted = stamp
        # The tick's time as fastep-sim counts it, k * dt: the stamp holds it to the nanosecond, and a time that
        # differs in its last bit decides a timer that runs out exactly on a tick differently.
        period = 1.0 / self.control_rate_hz
        t = round(stamp / period) * period
        scan, self.inputs.pending_scan = self.inputs.pending_scan, None
        if scan is not None and self.planning is not None:
            self.inputs.latest_scan = scan   # perceived by the next planning pass (realtime)
        elif scan is not None:
            belief = self.inputs.perceive(self.inputs.where(scan), t, at=t)
            if belief is not None:
                self.inputs.show_belief(belief)
        self.on_control(t)

    @quiet_at_stop
    def on_control_tick(self) -> None:
        """The control timer: act (without lock step), or in lock step act on the control timer only while the own
        odometry is a whole period behind the clock (the plant died or starves: the robot is held, `stale`)."""
        if not self.locked():
            self.on_control()
            return
        now, period = self.now(), 1.0 / self.control_rate_hz
        if self.inputs.odom_stamp < now - 1.5 * period and self.lock.acted < now - 0.5 * period:
            self.lock.acted = now
            self.on_control()
        else:
            self.lock_try()

    def on_control(self, at: float | None = None) -> None:
        """Decide and publish cmd_vel at node time `at` (lock step: the odometry stamp acted on), else now; its wall
        time goes into status' control_ms, its thread's CPU time into control_cpu_ms."""
        began, began_cpu = time.perf_counter(), time.thread_time()
        try:
            self.control(at)
        finally:
            self.reports.timed(time.perf_counter() - began, time.thread_time() - began_cpu)

    def control(self, at: float | None = None) -> None:
        """on_control's work."""
        if self.sim_time.switched():
            self.on_clock_switched()
        t = self.now() if at is None else at
        self.reports.control_stamps.append(t)
        self.take_others()
        nav = self.navigator
        command = np.zeros(2)
        if self.planning is not None:
            command = self.drive_on_plan(t)
        elif nav is not None:
            if not self.locked():
                self.inputs.retry_scans(t)
            state, problem = self.inputs.state(t)
            if state is None:
                self.hold = problem
            elif self.inputs.scans.hold(t)[1]:
                self.hold = ''   # held for its scans: status `blind` (fastep_ros.sensors)
            else:
                self.hold = ''
                others = self.inputs.other_robots(t)
                behaviour = behaviour_command(self, t, state, others)   # a behaviour under way drives instead
                command = behaviour if behaviour is not None else \
                    self.navigate(nav, t, state, others, self.inputs.velocity(), self.inputs.odom_stamp,
                                  self.inputs.odometry_state())
        self.publish_command(command, at)
        self.last_command = command
        if self.actions is not None:
            self.actions.check()
        if nav is not None:
            self.cost_pub.publish(cdr.float64_cdr(float(nav.cost)))
            self.publish_target()
            self.publish_plan()
        self.reports.publish(at=t)

    def drive_on_plan(self, t: float) -> np.ndarray:
        """With the planning thread: hand it this tick's snapshot and drive on the newest plan it has made
        (fastep_core.planning.control), never waiting for it."""
        assert self.planning is not None
        stop = np.zeros(2)
        nav, control = self.navigator, self.control_tick
        if nav is None or control is None:
            return stop
        period = 1.0 / self.control_rate_hz
        if not np.array_equal(self.last_command, control.smoother.velocity):
            control.reset(self.last_command)   # a stop sent past the control tick (inactive, no clock)
        state, problem = self.inputs.state(t)
        self.hold = problem
        if state is None:
            return control.stop(t, period)
        velocity, measured_at, pose = self.inputs.velocity(), self.inputs.odom_stamp, self.inputs.odometry_state()
        if not self.locked():
            self.inputs.retry_scans(t)
        if self.inputs.scans.hold(t)[1]:
            return control.stop(t, period, velocity, measured_at, pose)   # blind: status says why
        told = self.inputs.told_others(t)
        scan, self.inputs.latest_scan = self.inputs.latest_scan, None
        if scan is not None:
            scan = self.inputs.where(scan)   # odometry and TF read here, not on the planning thread
        self.control_count += 1
        self.planning.submit(PlanSnapshot(t, self.control_count, state, told, scan, velocity, measured_at,
                                          control.response.shown()))
        result = self.planning.plan   # read once: the plan with the tick it was planned from and its belief
        plan = None if result is None else result.plan
        if result is not None and result.belief is not None and result is not self._belief_shown:
            self._belief_shown = result
            self.inputs.tracked_pub.publish(result.belief)   # serialized by the pass: publishing costs no more
        # Age in control periods since the tick it was planned from: a simulated clock may jump between two ticks.
        age = 0.0 if result is None else (self.control_count - result.tick) / self.control_rate_hz
        if self.planning_stalled(t, result):
            return control.stop(t, period, velocity, measured_at, pose)
        if plan is not None and plan.under_way and age > self.max_plan_age:
            if not self.plan_problem:
                self.get_logger().error(f'planning stalled: the newest plan is {age:.2f} s old (max_plan_age '
                                        f'{self.max_plan_age:g} s); stopped until a pass ends')
            self.plan_problem = f'planning stalled: plan {age:.2f} s old (max_plan_age {self.max_plan_age:g} s)'
            return control.stop(t, period, velocity, measured_at, pose)
        self.plan_problem = ''
        plan = behaviour_plan(self, t, state, told, plan)   # a behaviour under way (spin, backup, ...) drives instead
        try:
            return control.command(t, state, told, plan, period, velocity, measured_at, pose)
        except Exception as exc:  # a fault of the control tick stops this robot, never the node
            if not self.fault_logged:
                self.get_logger().error(f'control fault: {exc}\n{traceback.format_exc()}')
                self.fault_logged = True
            self.change(FailGoal(f'control fault: {exc}'))
            return control.stop(t, period)

    def planning_stalled(self, t: float, result: PassResult | None) -> bool:
        """Has planning left no plan for planning_timeout while a goal is under way (no pass result new since: a
        pass that never ends)? Then the goal fails here, on the executor (`plan_failed`: status `failed`, an action
        goal aborted), and on the planning side once the pass ends (FailGoal); True while it is failed so."""
        if result is not self._result_seen or self._fresh_at == -math.inf:
            self._result_seen, self._fresh_at = result, t   # a pass ended (or a goal dropped its plan): fresh
        if self.plan_failed:
            if self.goal_msg is self._failed_goal:
                return True
            self.plan_failed, self._failed_goal, self._fresh_at = '', None, t   # a goal taken since
        nav = self.navigator
        under_way = nav is not None and self.goal is not None and nav.mode in (Mode.KINEMATIC, Mode.AVOIDING)
        if not under_way:
            self._fresh_at = t
            return False
        stalled = t - self._fresh_at
        if self.planning_timeout <= 0.0 or stalled < self.planning_timeout:
            return False
        self.plan_failed = f'planning timed out: no plan for {stalled:.1f} s (planning_timeout ' \
                           f'{self.planning_timeout:g} s)'
        self._failed_goal = self.goal_msg
        self.get_logger().error(f'{self.plan_failed}; the goal fails')
        self.change(FailGoal(self.plan_failed))   # applied on the planning side when the pass under way ends
        self.reports.changed()
        return True

    def plan_pass(self, snapshot: PlanSnapshot) -> PassResult | None:
        """One planning pass on the planning thread: perceive the newest scan, then the navigator's update; the plan
        leaves with the tick it was planned from and the belief to show (published by the executor)."""
        nav = self.navigator
        if nav is None:
            return None
        t, state = snapshot.t, snapshot.state
        if snapshot.response is not None:
            nav.take_response(snapshot.response)   # the base as measured when the snapshot was taken
        belief = None if snapshot.scan is None else \
            self.inputs.perceive(snapshot.scan, t, state=state, told=snapshot.others)
        # Its markers made and serialized here, published by the executor (building them took ~0.6 ms of a tick).
        shown = None if belief is None else serialize_message(self.inputs.belief_markers(belief))
        tracked = self.inputs.scan_perception.movers(t)
        command = self.navigate(nav, t, state, [*snapshot.others, *tracked], snapshot.velocity, snapshot.measured_at,
                                None)
        return PassResult(Plan.of(nav, t, command, tracked), snapshot.tick, shown, Way.of(nav))

    @property
    def plan_tick(self) -> int:
        """The control tick the newest plan was planned from (0: none yet)."""
        result = None if self.planning is None else self.planning.plan
        return 0 if result is None else result.tick

    def navigate(self, nav: Navigator, t: float, state: np.ndarray, others: list[OtherRobot],
                 velocity: np.ndarray | None, measured_at: float | None, pose: np.ndarray | None) -> np.ndarray:
        """The navigator's update (velocity: what the base measurably does, as of measured_at, with the odometry's
        own pose then); a fault of the planner fails its goal and stops this robot, never the node."""
        try:
            command = nav.update(t, state, others, velocity, measured_at, pose)
            if not np.all(np.isfinite(command)):
                raise FloatingPointError(f'command {command.tolist()} is not finite')
            return command
        except Exception as exc:  # a planner fault stops this robot, never the node
            if not self.fault_logged:
                self.get_logger().error(f'planner fault: {exc}\n{traceback.format_exc()}')
                self.fault_logged = True
            nav.fail(f'planner fault: {exc}')
            return np.zeros(2)

    def check_cmd_vel(self) -> bool:
        """Look for other publishers on cmd_vel (two planners in one namespace drove one robot by turns, and
        nothing said so); True if that changed. On a new conflict the robot is sent one zero, then nothing more
        while it lasts (exclusive_cmd_vel)."""
        topic = self.cmd_pub.topic_name
        try:
            others = self.count_publishers(topic) - 1
            if others > 0 or self.cmd_conflict:
                names = sorted(f'{i.node_namespace.rstrip("/")}/{i.node_name}'
                               for i in self.get_publishers_info_by_topic(topic))
                own = f'{self.get_namespace().rstrip("/")}/{self.get_name()}'
                if own in names:
                    names.remove(own)
                others = len(names)
        except Exception as exc:   # the graph can change under us: look again later
            self.get_logger().debug(f'graph look at {topic} failed: {exc}')
            return False
        conflict = f'{topic} has {others} other publisher{"s" if others > 1 else ""} ({", ".join(names)})' \
            if others > 0 else ''
        if conflict == self.cmd_conflict:
            return False
        if conflict and not self.cmd_conflict:
            if self.exclusive_cmd_vel and self.lifecycle.is_active:
                self.publish_command(np.zeros(2))
            then = 'this planner stops commanding' if self.exclusive_cmd_vel else \
                'commanding anyway (exclusive_cmd_vel false)'
            self.get_logger().error(f'{conflict}: two nodes commanding one robot; {then}')
        elif not conflict:
            self.get_logger().info(f'{topic} is this planner\'s alone again')
        self.cmd_conflict = conflict
        return True

    def publish_command(self, command: np.ndarray, at: float | None = None) -> None:
        """cmd_vel in the body frame: a point mass's map-frame velocity turned by its heading (the identity while
        map -> odom and the odometry's yaw are 0, as in simulation); (v, omega) are body-frame already. Stamped
        `at` (lock step: the time it was decided for), else now. Nothing while another node commands the robot
        too (check_cmd_vel)."""
        if self.cmd_conflict and self.exclusive_cmd_vel:
            return
        if self.model == 'point_mass':
            command = np.asarray(frames.body_velocity(command, self.inputs.body_yaw), dtype=float)
        # Sent as its bytes (msg_tools.cdr), once a tick: convert.command_to_twist's message, not built.
        linear, angular = convert.command_twist_values(command, self.model)
        if self.stamped:
            stamp = self.stamp_parts() if at is None else cdr.stamp_parts(at)
            self.cmd_pub.publish(cdr.twist_stamped_cdr(stamp, self.base_frame_id, linear, angular))
        else:
            self.cmd_pub.publish(cdr.twist_cdr(linear, angular))

    def publish_target(self, force: bool = False) -> None:
        nav = self.navigator
        # Only a robot under way has a target to show.
        target = nav.target if nav is not None and nav.mode in (Mode.KINEMATIC, Mode.AVOIDING) else None
        key = None if target is None else tuple(float(v) for v in target)
        if key is None or (key == self._target_key and not force):
            self._target_key = key
            return
        self._target_key = key
        # Sent as its bytes (msg_tools.cdr): convert.point_to_pose_stamped's message, not built.
        self.waypoint_pub.publish(cdr.pose_stamped_cdr(self.stamp_parts(), self.frame_id, (key[0], key[1])))

    def publish_plan(self, force: bool = False) -> None:
        nav = self.navigator
        if nav is None:
            return
        if self.planning is not None and self.planning.on_thread():
            self._plan_key = None   # the next control tick publishes it (publishers are the executor's)
            return
        points = [tuple(float(v) for v in p) for p in nav.plan]
        if self.goal is not None:
            points.append(self.goal)
        key = tuple(points)
        if key == self._plan_key and not force:
            return
        self._plan_key = key
        # Sent as its bytes (msg_tools.cdr): convert.waypoints_to_path's message, not built.
        self.plan_pub.publish(cdr.path_cdr(self.stamp_parts(), self.frame_id, points))

    @quiet_at_stop
    def on_wall_tick(self) -> None:
        """Every DISCOVERY_PERIOD wall seconds (START_PERIOD at first): look at the clock, discover robots; every
        HEARTBEAT, re-publish status, target and plan (for late listeners) and publish /diagnostics."""
        self.wall_ticks += 1
        if self.wall_ticks == START_LOOKS:
            self.wall_timer.timer_period_ns = round(DISCOVERY_PERIOD * 1e9)
        now = self.wall_clock.now().nanoseconds * 1e-9
        heartbeat = now - self.heartbeat_at >= HEARTBEAT - 0.5 * START_PERIOD
        if heartbeat:
            self.heartbeat_at = now
        self.check_clock()
        self.speed_limit_line.flush()   # the newest speed-limit change, once its period is over
        found = self.discover() | self.check_cmd_vel()
        self.goal_sub.look()
        for sub in self.inputs.world_subs:
            sub.look()
        if self.actions is not None:
            self.actions.check()   # also while no control tick runs (inactive: an action goal is aborted)
        self.take_others()   # while simulated time holds (no control ticks), `others` in the status still fills
        self.lock_try()      # an input waited for too long is given up on
        # A launcher waits for cmd_vel's readers (the plant, the clock) before it starts the run: told at once.
        readers = self.cmd_pub.get_subscription_count()
        if found or readers != self.reports.cmd_vel_readers or heartbeat:
            self.reports.cmd_vel_readers = readers
            self.reports.publish(force=True)
        else:
            self.reports.publish()
        if heartbeat:
            self.publish_target(force=True)
            self.publish_plan(force=True)
            self.reports.publish_diagnostics()
            late = self.reports.rate_problem()
            if late and self.lifecycle.is_active:
                self.get_logger().warning(late, throttle_duration_sec=10.0)

    # ------------------------------------------------------------------------------------------- time
    def check_clock(self) -> None:
        """On the wall clock: a switch of use_sim_time, a /clock that stopped (then the robot is stopped: a base
        without a command timeout would go on with the last command while the control loop stands still)."""
        if self.sim_time.switched():
            self.on_clock_switched()
        problem = self.sim_time.problem()
        if problem and not self.clock_problem:
            self.get_logger().warning(problem)
        self.clock_problem = problem
        if problem and np.any(self.last_command):
            self.last_command = np.zeros(2)
            self.publish_command(self.last_command)

    def on_clock_switched(self) -> None:
        """use_sim_time was switched: what was timed on the other clock restarts on this one.

        The control timer (on the node clock) stood still on simulated time without /clock, and the times kept
        (odometry's arrival, the navigator's timers) were read on the other clock: the odometry looked stale or
        from the future, and a switch back to wall time, years ahead, failed the progress checker.
        """
        t = self.now()
        self.get_logger().warning(f'use_sim_time is now {str(self.sim_time.active).lower()} (time {t:.3f} s): '
                                  'odometry and timers restart on this clock')
        inputs = self.inputs
        inputs.odom, inputs.odom_received, inputs.odom_stamp, inputs.odom_problem = None, -math.inf, -math.inf, ''
        inputs.scans.restart(t)
        for robot in self.robots.fleet.robots.values():
            if robot.received > -math.inf:   # kept where last heard, as if heard now: still avoided
                robot.received = robot.stamp = t
        self.change(RestartClock(t))
        self._fresh_at = -math.inf   # planning_timeout counts afresh on this clock
        self.last_command = np.zeros(2)
        self.publish_command(self.last_command)
        self.clock_problem = self.sim_time.problem()   # the silence counts from the switch
        self.reports.changed()


def main(args: Sequence[str] | None = None) -> int:
    return node_main('fastep-planner', PlannerNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
