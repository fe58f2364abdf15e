"""fastep-planner: FAStep-Kinematic (or ACO-Kinematic, Optimal-Kinematic, DWA) planning and control for one robot.

    fastep-planner --ros-args -r __ns:=/r1 -p algorithm:=fastep -p model:=point_mass -p robot_radius:=0.5

Every planner parameter of fastep_core (PlannerParams: Table 1 of the paper plus tolerances, speed limit,
progress checker...) is a ROS parameter of the same name, default and description.

Inputs: `odom` (and `trailer_pose` for tractor-trailers) of its own robot; `goal_pose`; `/obstacles`
(MarkerArray -> circles and segments) and `/map` (OccupancyGrid: only its extent, the workspace, is used,
unless the `workspace` parameter gives it), both transient-local; and the `odom` of every other robot,
discovered from the graph every 0.25 s of wall time (topics `/<name>/odom` of type nav_msgs/msg/Odometry).
Odometry is predicted forward from its stamp to the control time (at most max_extrapolation seconds) to make
up for the transport delay. Own odometry stamped longer ago than that (an unset stamp counts as its arrival)
is not acted on: the robot is held still (zero cmd_vel, `stale`) until fresher odometry comes, because a
command decided and guarded at a position the robot has left can drive it into an obstacle (docs/robustness.md,
"A loaded machine").

Outputs, on a control timer of the node clock (simulated time with use_sim_time): `cmd_vel`, `cost`; and when
they change (and once a wall second): `waypoint` (the point driven to now), `plan` (the waypoints planned so
far and the goal) and `status` (diagnostic_msgs/DiagnosticStatus: name = the namespace, message = mode, values
reason / activations / escapes / manoeuvres / waypoint / goal / cost / algorithm / t / odom_lag / obstacles,
and for a launcher: others (the robots whose odometry it has heard), cmd_vel_readers (subscriptions matched to
cmd_vel) and odom_heard (own odometry messages taken)).

status.message is the navigator mode (idle, kinematic, avoiding, arrived, failed) or, when the planner cannot
run it, `waiting` (world or odometry not received yet) or `stale` (no odometry for odom_timeout, odometry
stamped more than max_extrapolation before the control time or more than odom_timeout after it, received
before the clock went back, or not finite; zero cmd_vel is sent). Levels: OK
(idle, kinematic, avoiding, arrived), WARN (waiting, stale), ERROR (failed, which includes a refused goal:
reason is the goal check's message, e.g. "... is occupied ...").
"""

from __future__ import annotations

import functools
import math
import traceback
from dataclasses import dataclass, fields
from typing import Any, Sequence

import numpy as np
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
from nav_msgs.msg import OccupancyGrid, Odometry, Path
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from std_msgs.msg import Float64
from visualization_msgs.msg import MarkerArray

from fastep_core.errors import GoalError, ParameterError
from fastep_core.planning.algorithms import ALGORITHMS, DEFAULT_ALGORITHM, algorithm_name, check_drives, make_navigator
from fastep_core.planning.navigator import Mode, Navigator
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.params import PlannerParams
from fastep_core.world import World
from fastep_ros.common import RATE_RANGE, StartupError, check_range, declare, guard_clock, node_main
from fastep_ros.limits import GRAPH_MODELS as MODELS  # diff_drive: not on the graph yet (limits.py)
from msg_tools import convert, interface
from msg_tools.interface import LATCHED, LATEST, RELIABLE, offered_qos

__all__ = ['PlannerNode', 'main']

DISCOVERY_PERIOD = 0.25  # wall seconds between looks at the graph for other robots
HEARTBEAT_TICKS = 4      # status, waypoint and plan are re-published every 4 * 0.25 s = 1 s of wall time


def stream_rng(seed: int, stream: int) -> np.random.Generator:
    """default_rng(seed) for stream -1, else the generator of SeedSequence(seed).spawn(stream + 1)[stream] (what
    fastep-sim gives its stream-th robot), built directly: spawn made every child before it, and stream 2e9 grew
    the planner by ~85 MB/s (a spawned child is SeedSequence(seed, spawn_key=(its index,)))."""
    if stream < 0:
        return np.random.default_rng(seed)
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(stream,)))


@dataclass(frozen=True)
class _Body:
    """What make_robot needs to know about the robot."""

    model: str
    length: float
    trailer_length: float
    hitch_offset: float


@dataclass
class _Other:
    name: str
    position: tuple[float, float] | None = None
    velocity: tuple[float, float] = (0.0, 0.0)
    received: float = -math.inf
    stamp: float = 0.0


class PlannerNode(Node):
    """One robot's navigator (fastep_core) between its odometry and its cmd_vel."""

    def __init__(self, node_name: str = 'planner', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        guard_clock(self)   # a bad /clock message is ignored, never the end of the node
        self.params = self._declare_planner_params()
        self.algorithm = declare(self, 'algorithm', DEFAULT_ALGORITHM,
                                 'planner: ' + ', '.join(f'{a} ({algorithm_name(a)})' for a in ALGORITHMS),
                                 constraints=' | '.join(ALGORITHMS))
        self.model = declare(self, 'model', 'point_mass', 'robot model: point_mass | tractor_trailer',
                             constraints='point_mass | tractor_trailer')
        self.radius = declare(self, 'robot_radius', 0.5, 'safety radius: centre-to-obstacle-surface distance '
                              'that counts as collision (m)', constraints='> 0')
        length = declare(self, 'length', 1.0, 'tractor-trailer: tractor mid-axle length L (m)')
        trailer_length = declare(self, 'trailer_length', 1.0, 'tractor-trailer: trailer length Lt (m)')
        hitch_offset = declare(self, 'hitch_offset', 0.0, 'tractor-trailer: hitch offset c (m)')
        self.seed = declare(self, 'seed', 0, 'seed of the swarm\'s random numbers')
        self.seed_stream = declare(self, 'seed_stream', -1, 'if >= 0: use stream k of SeedSequence(seed).spawn, '
                                   'as fastep-sim does for the k-th robot of a scenario; -1: default_rng(seed)')
        self.control_rate_hz = declare(self, 'control_rate_hz', 20.0, 'control ticks per second of the node '
                                       'clock (1 / dt of the in-process simulator)',
                                       constraints=f'range [{RATE_RANGE[0]:g}, {RATE_RANGE[1]:g}]')
        self.odom_timeout = declare(self, 'odom_timeout', 1.0, 'odometry older than this (s, node clock) is '
                                    'stale: the robot is stopped', constraints='> 0')
        stamped = declare(self, 'use_stamped_cmd_vel', False, 'publish cmd_vel as TwistStamped, not Twist')
        other_radius = declare(self, 'other_robot_radius', 0.0, 'safety radius assumed for other robots (m); '
                               '0 means robot_radius', constraints='>= 0')
        self.max_extrapolation = declare(
            self, 'max_extrapolation', 0.25, 'latency compensation: odometry (own and other robots\') is '
            'predicted forward from its stamp to the control time by at most this much (s); own odometry stamped '
            'longer ago is stale: the robot is held still; 0 disables both', constraints='>= 0')
        workspace = declare(self, 'workspace', None, '[xmin, ymin, xmax, ymax] (m); empty: the extent of /map')
        self.frame_id = declare(self, 'frame_id', interface.MAP_FRAME, 'frame of goals, waypoints and plans')
        self._check(length, trailer_length, hitch_offset, other_radius, workspace)
        self.other_radius = other_radius if other_radius > 0.0 else self.radius
        self.body = _Body(self.model, length, trailer_length, hitch_offset)
        self.stamped = stamped
        self.workspace_param: tuple[float, float, float, float] | None = (
            tuple(workspace) if workspace else None)
        self.rng = stream_rng(self.seed, self.seed_stream)

        # What the planner knows.
        self.obstacles: list[Any] | None = None
        self.map_workspace: tuple[float, float, float, float] | None = None
        self.world: World | None = None
        self.navigator: Navigator | None = None
        self.pending_goal: PoseStamped | None = None
        self.goal: tuple[float, float] | None = None
        self.odom: Odometry | None = None
        self.odom_received = -math.inf
        self.odom_stamp = -math.inf   # its header stamp; when it arrived if that is unset (zero)
        self.odom_problem = ''
        self.odom_heard = 0            # own odometry messages taken
        self.trailer: float | None = None
        self.others: dict[str, _Other] = {}
        self.other_subs: dict[str, Any] = {}
        self.fault_logged = False
        self.hold = ''  # why the robot is held still although it has a goal ('' when it is not)
        self.last_command = np.zeros(2)
        self.odom_lag = 0.0
        # What was last published.
        self._status_key: tuple[Any, ...] | None = None
        self._plan_key: tuple[Any, ...] | None = None
        self._target_key: tuple[float, ...] | None = None

        self.cmd_pub = self.create_publisher(TwistStamped if stamped else Twist, interface.CMD_VEL,
                                             offered_qos(interface.CMD_VEL))
        self.waypoint_pub = self.create_publisher(PoseStamped, interface.WAYPOINT, offered_qos(interface.WAYPOINT))
        self.plan_pub = self.create_publisher(Path, interface.PLAN, offered_qos(interface.PLAN))
        self.cost_pub = self.create_publisher(Float64, interface.COST, offered_qos(interface.COST))
        self.status_pub = self.create_publisher(DiagnosticStatus, interface.STATUS, offered_qos(interface.STATUS))
        self.odom_sub = self.create_subscription(Odometry, interface.ODOM, self.on_odom, LATEST)
        if self.model == 'tractor_trailer':
            self.create_subscription(PoseStamped, interface.TRAILER_POSE, self.on_trailer, LATEST)
        # Goals from anyone (volatile, as `ros2 topic pub` sends them) and from latched publishers (fastep-launch):
        # a planner restarted mid-run gets the goal it was driving to again and resumes from the odometry.
        self.create_subscription(PoseStamped, interface.GOAL_POSE, self.on_goal, RELIABLE)
        self.create_subscription(PoseStamped, interface.GOAL_POSE, self.on_goal, LATCHED)
        self.create_subscription(MarkerArray, interface.OBSTACLES, self.on_obstacles, offered_qos(interface.OBSTACLES))
        if self.workspace_param is None:
            self.create_subscription(OccupancyGrid, interface.MAP, self.on_map, offered_qos(interface.MAP))
        self.own_odom_topic = self.odom_sub.topic_name
        self.control_timer = self.create_timer(1.0 / self.control_rate_hz, self.on_control)
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.wall_ticks = 0
        self.wall_timer = self.create_timer(DISCOVERY_PERIOD, self.on_wall_tick, clock=steady)
        self.discover()
        self.update_world()
        self.get_logger().info(f'{self.algorithm} planner for a {self.model} of radius {self.radius:g} m, '
                               f'control at {self.control_rate_hz:g} Hz')

    # ------------------------------------------------------------------------------------------- setup
    def _declare_planner_params(self) -> PlannerParams:
        defaults = PlannerParams()
        values = {}
        for f in fields(PlannerParams):
            low, high = f.metadata['range']
            values[f.name] = declare(self, f.name, getattr(defaults, f.name), f.metadata['description'],
                                     constraints=f'range [{low:g}, {high:g}]')
        try:
            return defaults.with_overrides(values)
        except ParameterError as exc:
            raise StartupError(str(exc)) from None

    def _check(self, length: float, trailer_length: float, hitch_offset: float, other_radius: float,
               workspace: list[float]) -> None:
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
        if hitch_offset < 0.0 or other_radius < 0.0 or self.max_extrapolation < 0.0:
            raise StartupError('parameters hitch_offset, other_robot_radius and max_extrapolation must be >= 0')
        if workspace and (len(workspace) != 4 or not (workspace[0] < workspace[2] and workspace[1] < workspace[3])):
            raise StartupError(f'parameter workspace must be [xmin, ymin, xmax, ymax] with min < max, got {workspace}')

    # ------------------------------------------------------------------------------------------- helpers
    def now(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    def stamp(self) -> Any:
        return self.get_clock().now().to_msg()

    # ------------------------------------------------------------------------------------------- the world
    def on_obstacles(self, msg: MarkerArray) -> None:
        try:
            self.obstacles = convert.marker_array_to_obstacles(msg)
        except ValueError as exc:
            self.get_logger().error(f'ignoring /obstacles: {exc}')
            return
        self.update_world()

    def on_map(self, msg: OccupancyGrid) -> None:
        try:
            self.map_workspace = convert.occupancy_grid_workspace(msg)
        except ValueError as exc:
            self.get_logger().error(f'ignoring /map: {exc}')
            return
        self.update_world()

    def update_world(self) -> None:
        workspace = self.workspace_param or self.map_workspace
        if self.obstacles is None or workspace is None:
            return
        self.world = World.from_obstacles(workspace, self.obstacles)
        if self.navigator is None:
            self.navigator = make_navigator(self.algorithm, self.body, self.radius, self.world, self.params,
                                            self.rng)
            self.get_logger().info(f'world known: {len(self.obstacles)} obstacles in {workspace}')
        else:
            self.navigator.world = self.world
            self.get_logger().info(f'world updated: {len(self.obstacles)} obstacles')
        self._status_key = None   # the obstacle count is part of the status
        if self.pending_goal is not None:
            goal, self.pending_goal = self.pending_goal, None
            self.on_goal(goal)
        self.publish_status()

    # ------------------------------------------------------------------------------------------- inputs
    def on_odom(self, msg: Odometry) -> None:
        try:
            convert.odometry_position(msg)
            convert.quaternion_to_yaw(msg.pose.pose.orientation)
        except ValueError as exc:
            self.odom_problem = f'odometry rejected: {exc}'
            self.get_logger().warning(self.odom_problem, throttle_duration_sec=5.0)
            return
        self.odom, self.odom_received, self.odom_problem = msg, self.now(), ''
        stamp = convert.stamp_to_seconds(msg.header.stamp)
        self.odom_stamp = stamp if stamp > 0.0 else self.odom_received
        self.odom_heard += 1
        if self.odom_heard == 1:
            self.publish_status(force=True)   # a launcher waits for the odometry path to be up

    def on_trailer(self, msg: PoseStamped) -> None:
        try:
            self.trailer = convert.trailer_yaw(msg)
        except ValueError as exc:
            self.odom_problem = f'trailer pose rejected: {exc}'
            self.get_logger().warning(self.odom_problem, throttle_duration_sec=5.0)

    def on_goal(self, msg: PoseStamped) -> None:
        point = convert.pose_stamped_to_point(msg)
        if self.navigator is None:
            self.pending_goal = msg
            self.get_logger().info(f'goal ({point[0]:g}, {point[1]:g}) received; waiting for the world')
            self.publish_status()
            return
        frame = msg.header.frame_id
        nav = self.navigator
        if self.goal is not None and nav.mode in (Mode.KINEMATIC, Mode.AVOIDING) and \
                tuple(float(v) for v in point) == self.goal:
            return   # the goal driven to already (a latched goal seen twice, or sent again): nothing changes
        try:
            if frame not in ('', 'map', self.frame_id):
                raise GoalError(f'goal frame {frame!r} is not {self.frame_id!r} (no transforms here)')
            self.navigator.set_goal(point, self.now())
        except GoalError as exc:
            self.goal = None
            self.navigator.fail(f'goal refused: {exc}')
            self.get_logger().warning(f'goal refused: {exc}')
        else:
            self.goal = (float(point[0]), float(point[1]))
            self.get_logger().info(f'new goal ({point[0]:g}, {point[1]:g})')
        self.publish_plan(force=True)
        self.publish_status()

    def discover(self) -> bool:
        """Subscribe to the odometry of every other robot on the graph; True if one was new."""
        found = False
        for topic, types in self.get_topic_names_and_types():
            suffix = '/' + interface.ODOM
            if not topic.endswith(suffix) or interface.TYPES[interface.ODOM] not in types or \
                    topic == self.own_odom_topic:
                continue
            if topic in self.other_subs:
                continue
            name = topic[1:-len(suffix)] or topic
            self.others[topic] = _Other(name)
            self.other_subs[topic] = self.create_subscription(
                Odometry, topic, functools.partial(self.on_other_odom, topic), LATEST)
            self.get_logger().info(f'following robot {name} on {topic}')
            found = True
        return found

    def on_other_odom(self, topic: str, msg: Odometry) -> None:
        other = self.others[topic]
        try:
            other.position = convert.odometry_position(msg)
            other.velocity = convert.odometry_velocity(msg)
        except ValueError as exc:
            self.get_logger().warning(f'ignoring odometry of {other.name}: {exc}', throttle_duration_sec=5.0)
            return
        first = other.received == -math.inf
        other.received = self.now()
        other.stamp = convert.stamp_to_seconds(msg.header.stamp)
        if first:
            self.publish_status(force=True)   # `others` lists the robots heard

    def other_robots(self, t: float) -> list[OtherRobot]:
        out = []
        for other in self.others.values():
            if other.position is None:
                continue
            # A robot whose odometry stopped is still there, but no longer known to move.
            velocity = other.velocity if t - other.received <= self.odom_timeout else (0.0, 0.0)
            lag = self.lag(t, other.stamp)
            position = (other.position[0] + velocity[0] * lag, other.position[1] + velocity[1] * lag)
            out.append(OtherRobot(other.name, position, velocity, self.other_radius))
        return out

    # ------------------------------------------------------------------------------------------- control
    def state(self, t: float) -> tuple[np.ndarray | None, str]:
        """The robot's state, or None and why the robot must hold still."""
        if self.odom_problem:
            return None, self.odom_problem
        if self.odom is None:
            return None, f'waiting for odometry on {self.own_odom_topic}'
        if t - self.odom_received > self.odom_timeout:
            return None, f'odometry stale: none for {t - self.odom_received:.2f} s (odom_timeout ' \
                         f'{self.odom_timeout:g} s)'
        if t < self.odom_received:
            # The clock went back since it came (a restarted clock): how old it is is not known.
            return None, f'odometry stale: received at {self.odom_received:.2f} s, after this node\'s clock ' \
                         f'({t:.2f} s): the clock went back'
        if self.model == 'tractor_trailer' and self.trailer is None:
            return None, 'waiting for trailer_pose'
        try:
            state = convert.odometry_to_state(self.odom, self.model, self.trailer)
        except ValueError as exc:
            return None, f'odometry rejected: {exc}'
        self.odom_lag = t - self.odom_stamp
        if self.odom_lag < -self.odom_timeout:
            # From a clock that ran ahead of this node's (a restarted plant, a clock jump): acting on it would
            # take a position the robot has left for its present one.
            return None, (f'odometry stale: stamped {-self.odom_lag:.2f} s ahead of this node\'s clock '
                          f'(odom_timeout {self.odom_timeout:g} s)')
        if self.max_extrapolation > 0.0 and self.odom_lag > self.max_extrapolation:
            # Where the robot is now cannot be predicted that far: a command from this state would be checked (by
            # the guard) at a position the robot has left.
            return None, (f'odometry stale: stamped {self.odom_lag:.2f} s ago, beyond what it is predicted over '
                          f'(max_extrapolation {self.max_extrapolation:g} s)')
        lag = self.lag(t, self.odom_stamp)
        if lag > 0.0 and self.navigator is not None:
            # Latency compensation: the plant has applied the last command since the odometry was stamped.
            state = self.navigator.model.integrate(state, self.last_command, lag)
        return state, ''

    def lag(self, t: float, stamp: float) -> float:
        """How far to predict a message stamped `stamp` forward to the control time t."""
        return min(max(t - stamp, 0.0), self.max_extrapolation)

    def on_control(self) -> None:
        t = self.now()
        nav = self.navigator
        command = np.zeros(2)
        if nav is not None:
            state, problem = self.state(t)
            if state is None:
                self.hold = problem
            else:
                self.hold = ''
                try:
                    command = nav.update(t, state, self.other_robots(t))
                    if not np.all(np.isfinite(command)):
                        raise FloatingPointError(f'command {command.tolist()} is not finite')
                except Exception as exc:  # a planner fault stops this robot, never the node
                    command = np.zeros(2)
                    if not self.fault_logged:
                        self.get_logger().error(f'planner fault: {exc}\n{traceback.format_exc()}')
                        self.fault_logged = True
                    nav.fail(f'planner fault: {exc}')
        self.publish_command(command)
        self.last_command = command
        if nav is not None:
            self.cost_pub.publish(Float64(data=float(nav.cost)))
            self.publish_target()
            self.publish_plan()
        self.publish_status()

    def publish_command(self, command: np.ndarray) -> None:
        twist = convert.command_to_twist(command, self.model)
        if self.stamped:
            msg = TwistStamped()
            msg.header.stamp = self.stamp()
            msg.header.frame_id = self.get_namespace().strip('/') + '/base_link' if self.model == \
                'tractor_trailer' else self.frame_id
            msg.twist = twist
            self.cmd_pub.publish(msg)
        else:
            self.cmd_pub.publish(twist)

    def publish_target(self, force: bool = False) -> None:
        nav = self.navigator
        # Only a robot under way has a target to show.
        target = nav.target if nav is not None and nav.mode in (Mode.KINEMATIC, Mode.AVOIDING) else None
        key = None if target is None else tuple(float(v) for v in target)
        if key is None or (key == self._target_key and not force):
            self._target_key = key
            return
        self._target_key = key
        self.waypoint_pub.publish(convert.point_to_pose_stamped(key, self.stamp(), self.frame_id))

    def publish_plan(self, force: bool = False) -> None:
        nav = self.navigator
        if nav is None:
            return
        points = [tuple(float(v) for v in p) for p in nav.plan]
        if self.goal is not None:
            points.append(self.goal)
        key = tuple(points)
        if key == self._plan_key and not force:
            return
        self._plan_key = key
        self.plan_pub.publish(convert.waypoints_to_path(points, self.stamp(), self.frame_id))

    # ------------------------------------------------------------------------------------------- status
    def status(self) -> tuple[bytes, str, str]:
        nav = self.navigator
        if nav is None:
            missing = [name for name, have in ((interface.OBSTACLES, self.obstacles is not None),
                                               (interface.MAP, self.workspace_param or self.map_workspace))
                       if not have]
            return DiagnosticStatus.WARN, 'waiting', f'waiting for the world ({" and ".join(missing)})'
        mode = nav.mode
        if mode is Mode.FAILED:
            return DiagnosticStatus.ERROR, mode.value, nav.reason
        if mode in (Mode.IDLE, Mode.ARRIVED):
            return DiagnosticStatus.OK, mode.value, nav.reason
        if self.hold:
            if self.hold.startswith('waiting'):
                return DiagnosticStatus.WARN, 'waiting', self.hold
            return DiagnosticStatus.WARN, 'stale', self.hold
        return DiagnosticStatus.OK, mode.value, nav.reason

    def publish_status(self, force: bool = False) -> None:
        level, message, reason = self.status()
        key = (level, message, reason)
        if key == self._status_key and not force:
            return
        self._status_key = key
        nav = self.navigator
        waypoint = None if nav is None or nav.waypoint is None else nav.waypoint
        values = {
            'reason': reason,
            'activations': 0 if nav is None else nav.activations,
            'escapes': 0 if nav is None else nav.escapes,
            'manoeuvres': 0 if nav is None else nav.manoeuvres,
            'waypoint': waypoint,
            'goal': self.goal,
            'cost': 0.0 if nav is None else float(nav.cost),
            'others': ' '.join(sorted(o.name for o in self.others.values() if o.position is not None)),
            'algorithm': self.algorithm,
            't': self.now(),
            'odom_lag': self.odom_lag,
            'obstacles': -1 if self.obstacles is None else len(self.obstacles),
            # Who hears cmd_vel (the plant; the clock's lock step): the readers this writer has matched. DDS
            # matches each end on its own, so that the plant's end is matched too is told by ...
            'cmd_vel_readers': self.cmd_pub.get_subscription_count(),
            # ... its odometry having reached this planner: while simulated time holds at 0 a plant publishes
            # its start state once its cmd_vel reader is matched (odometry is volatile: a match is not a delivery).
            'odom_heard': self.odom_heard,
        }
        self.status_pub.publish(convert.make_status(self.get_namespace(), message, level, values))

    def on_wall_tick(self) -> None:
        """Every DISCOVERY_PERIOD wall seconds: discover robots; once a wall second, re-publish status, target
        and plan (for late listeners)."""
        self.wall_ticks += 1
        found = self.discover()
        if found or self.wall_ticks % HEARTBEAT_TICKS == 0:
            self.publish_status(force=True)
        if self.wall_ticks % HEARTBEAT_TICKS == 0:
            self.publish_target(force=True)
            self.publish_plan(force=True)


def main(args: Sequence[str] | None = None) -> int:
    return node_main('fastep-planner', PlannerNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
