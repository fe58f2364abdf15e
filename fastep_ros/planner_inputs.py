"""What the planner node hears, and the robot's state it makes of it: the world (/obstacles, /map), its robot's
odometry, localization and trailer pose, the movers (/movers) and its own scans.

Apart from the node (fastep_ros/planner.py: parameters, goals, lock step, the control loop) because these are the
handlers of its inputs and the state they give, one concern. `PlannerInputs` is PlannerNode's base, under
PlannerReports: PlannerNode sets every attribute it declares and supplies `lock_try` and `on_goal`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid, Odometry
from rclpy.publisher import Publisher
from sensor_msgs.msg import LaserScan
from visualization_msgs.msg import MarkerArray

from fastep_core.perception.belief import heading
from fastep_core.planning.algorithms import make_navigator
from fastep_core.planning.control import ControlTick, Plan
from fastep_core.planning.navigator import Navigator
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.params import PlannerParams
from fastep_core.sensing.laser import way_problem
from fastep_core.world import World
from fastep_ros.lifecycle import ManagedNode
from fastep_ros.live_tf import TfListener
from fastep_ros.lock_step import STAMP_EPS, LockStep
from fastep_ros.perception import ScanPerception
from fastep_ros.planner_status import PlannerReports
from fastep_ros.planning_thread import PlanningThread
from fastep_ros.robots import RobotFollower, robot_name
from fastep_ros.sim_time import SimTimeWatch
from msg_tools import convert, frames, interface

__all__ = ['Body', 'PlannerInputs']


@dataclass(frozen=True)
class Body:
    """What make_robot needs to know about the robot."""

    model: str
    length: float
    trailer_length: float
    hitch_offset: float


class PlannerInputs(ManagedNode):
    """The input handlers and the robot's state of the planner node (fastep_ros.planner.PlannerNode derives from it)."""

    # What the handlers read and set, set up by PlannerNode.
    params: PlannerParams
    model: str
    body: Body
    radius: float
    rng: np.random.Generator
    frame_id: str
    odom_frame_id: str
    localization_topic: str
    obstacle_source: str
    occupied_threshold: int
    occupied: Callable[[Sequence[float]], bool] | None
    world: World | None
    pending_goal: PoseStamped | None
    pending_scan: LaserScan | None
    odom_stamp: float
    map_from_odom: frames.MapFromOdom
    trailer: float | None
    trailer_stamp: float
    body_yaw: float
    last_command: np.ndarray
    max_extrapolation: float
    known_movers: list[OtherRobot]
    movers_stamp: float
    map_to_odom_from_tf: bool
    tf: TfListener
    tracked_pub: Publisher
    lock_step: bool
    lock: LockStep
    base_frame_id: str
    laser_mount: frames.Pose2D | None
    planning: PlanningThread[Any, Plan] | None
    control_tick: ControlTick | None
    latest_scan: LaserScan | None
    algorithm: str
    navigator: Navigator | None
    goal: tuple[float, float] | None
    hold: str                      # why the robot is held still although it has a goal ('' when it is not)
    cmd_conflict: str              # the other publishers on cmd_vel ('' when there are none)
    exclusive_cmd_vel: bool
    goal_refused: str              # why the last goal was refused, while the goal before it is driven to
    clock_problem: str             # why this node's time stands still ('' when it does not)
    obstacles: list[Any] | None
    workspace_param: tuple[float, float, float, float] | None
    map_workspace: tuple[float, float, float, float] | None
    odom: frames.StampedPose | None
    odom_received: float
    odom_timeout: float
    odom_problem: str
    odom_heard: int
    odom_lag: float
    own_odom_topic: str
    control_rate_hz: float
    plan_problem: str              # why the plan is not driven on ('' when it is)
    control_count: int
    plan_tick: int
    robots: RobotFollower
    cmd_pub: Publisher
    scan_perception: ScanPerception
    scan_problem: str
    sim_time: SimTimeWatch
    movers_received: float
    _stale_logged: list[str]
    reports: PlannerReports

    def now(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    def movers_stale(self, t: float) -> bool:
        """Whether the known movers are older than odom_timeout (the map node stopped or stalled), or stamped
        further than that ahead of this node's clock."""
        return bool(self.known_movers) and not (t - self.movers_received <= self.odom_timeout and
                                                -self.odom_timeout <= t - self.movers_stamp <= self.odom_timeout)

    def stale_inputs(self, t: float) -> list[tuple[str, float]]:
        """What this robot avoids on data that stopped coming, and how old that data is: other robots whose
        odometry stopped (by name; fastep_ros.robots), the known movers ('/movers'). Logged when that changes."""
        stale = [(r.name, t - r.received) for r in self.robots.fleet.stale(t)]
        if self.movers_stale(t):
            stale.append((interface.MOVERS, t - self.movers_received))
        names = [name for name, _ in stale]
        if names != self._stale_logged:
            went, back = [n for n in names if n not in self._stale_logged], \
                [n for n in self._stale_logged if n not in names]
            if went:
                self.get_logger().warning(f'stale: {", ".join(went)}; avoided where last seen, the reach widening '
                                          f'at the last speed known, until fresh data comes')
            if back:
                self.get_logger().info(f'fresh again: {", ".join(back)}')
            self._stale_logged = names
        return stale

    def lock_try(self) -> None:
        """Lock step: act once every input of the newest odometry's time is in (PlannerNode's)."""
        raise NotImplementedError

    def on_goal(self, msg: PoseStamped) -> None:
        """A goal (PlannerNode's: one that came before the world is taken once the world is known)."""
        raise NotImplementedError

    def change(self, work: Callable[[], Any]) -> None:
        """Change the navigator between two planning passes (PlannerNode's)."""
        raise NotImplementedError

    def locked(self) -> bool:
        """Lock step is on: asked for, and the node runs on simulated time."""
        return self.lock_step and self.sim_time.active

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
            workspace = convert.occupancy_grid_workspace(msg)
            obstacles = (convert.occupancy_grid_obstacles(msg, self.occupied_threshold)
                         if self.obstacle_source == 'map' else None)
        except ValueError as exc:
            self.get_logger().error(f'ignoring /map: {exc}')
            return
        self.map_workspace = workspace
        if obstacles is not None:   # obstacle_source map: the occupied cells' outline (msg_tools.convert)
            self.obstacles = list(obstacles)
            self.occupied = convert.occupancy_grid_lookup(msg, self.occupied_threshold)
        self.update_world()

    def update_world(self) -> None:
        workspace = self.workspace_param or self.map_workspace
        if self.obstacles is None or workspace is None:
            return
        self.world = world = World.from_obstacles(workspace, self.obstacles)
        count = len(self.obstacles)

        def adopt() -> None:
            self.scan_perception.reset()   # a new map: what the scans showed is believed afresh on it
            if self.navigator is None:
                self.navigator = nav = make_navigator(self.algorithm, self.body, self.radius, world, self.params,
                                                      self.rng)
                nav.name = robot_name(self.get_namespace())   # as the other robots' planners name it
                if self.planning is not None:
                    self.planning.drop_plan()
                    self.control_tick = ControlTick(nav)
                self.get_logger().info(f'world known: {count} obstacles in {workspace}')
            else:
                self.navigator.world = world
                self.get_logger().info(f'world updated: {count} obstacles')
            self.reports.changed()   # the obstacle count is part of the status
            if self.pending_goal is not None:
                goal, self.pending_goal = self.pending_goal, None
                self.on_goal(goal)
            self.reports.publish()
        self.change(adopt)

    # ------------------------------------------------------------------------------------------- inputs
    def on_odom(self, msg: Odometry | bytes) -> None:
        """The robot's own odometry: a message, or its bytes (the subscription's: read with msg_tools.cdr)."""
        try:
            odom = frames.stamped_pose(msg)
            frame, pose, stamp = odom.frame_id, odom.pose, odom.stamp
            if frame not in (self.frame_id, self.odom_frame_id):
                raise ValueError(f'frame {frame!r} is neither the map frame {self.frame_id!r} nor this robot\'s odom '
                                 f'frame {self.odom_frame_id!r} (parameters frame_id, odom_frame_id)')
        except ValueError as exc:
            self.odom_problem = f'odometry rejected: {exc}'
            self.get_logger().warning(self.odom_problem, throttle_duration_sec=5.0)
            return
        now = self.now()
        # In lock step odometry is of its stamp's time: the start state (stamped 0) is heard again once time runs.
        self.odom, self.odom_received, self.odom_problem = odom, min(now, stamp) if self.locked() else now, ''
        self.odom_stamp = stamp if stamp > 0.0 else self.odom_received
        # Kept in either frame: localization finds the odometry of its stamp in it, a scan the pose of its stamp.
        self.map_from_odom.add_odometry(self.odom_stamp, pose)
        self.odom_heard += 1
        if self.odom_heard == 1:
            self.reports.publish(force=True)   # a launcher waits for the odometry path to be up
        self.lock_try()

    def on_localization(self, msg: PoseWithCovarianceStamped) -> None:
        """A map pose of base_link: map -> odom = it o inverse(the odometry at its stamp)."""
        try:
            if msg.header.frame_id not in ('', self.frame_id):
                raise ValueError(f'frame {msg.header.frame_id!r} is not the map frame {self.frame_id!r}')
            pose = frames.odometry_pose(msg)
        except ValueError as exc:
            self.get_logger().warning(f'localization pose ignored: {exc}', throttle_duration_sec=5.0)
            return
        stamp = convert.stamp_to_seconds(msg.header.stamp)
        self.map_from_odom.add_localization(stamp if stamp > 0.0 else self.now(), pose)

    def map_to_odom(self) -> frames.Pose2D | None:
        """map -> odom of the odometry last taken (None: not known yet, the robot holds still): from the
        localization pose topic, else from TF (map_to_odom_from_tf), else the identity (simulation)."""
        if self.odom is None or self.odom.frame_id == self.frame_id:
            return frames.IDENTITY
        if self.localization_topic:
            return self.map_from_odom.transform
        if self.map_to_odom_from_tf:
            return self.tf.lookup(self.frame_id, self.odom_frame_id)
        return frames.IDENTITY

    def on_trailer(self, msg: PoseStamped) -> None:
        try:
            self.trailer = convert.trailer_yaw(msg)
        except ValueError as exc:
            self.odom_problem = f'trailer pose rejected: {exc}'
            self.get_logger().warning(self.odom_problem, throttle_duration_sec=5.0)
            return
        self.trailer_stamp = convert.stamp_to_seconds(msg.header.stamp)
        self.lock_try()

    def other_robots(self, t: float) -> list[OtherRobot]:
        """The other robots (their odometry), the known movers (/movers) and the movers this robot's scans track."""
        return [*self.told_others(t), *self.scan_perception.movers(t)]

    def told_others(self, t: float) -> list[OtherRobot]:
        """The other robots (their odometry) and the known movers (/movers): what the robot is told of."""
        robots = self.robots.fleet.obstacles(t, self.robots.radius, lambda stamp: self.lag(t, stamp))
        return [*robots, *self.movers_at(t)]

    def on_movers(self, msg: MarkerArray) -> None:
        try:
            movers = convert.marker_array_to_movers(msg)
        except ValueError as exc:
            self.get_logger().warning(f'ignoring /movers: {exc}', throttle_duration_sec=5.0)
            return
        # Every marker after the leading DELETEALL carries the map node's stamp; unset: when it came.
        stamp = convert.stamp_to_seconds(msg.markers[1].header.stamp) if len(msg.markers) > 1 else 0.0
        self.known_movers = movers
        self.movers_received = self.now()
        self.movers_stamp = stamp if stamp > 0.0 else self.movers_received

    def movers_at(self, t: float) -> list[OtherRobot]:
        """The known movers predicted from their stamp to t (at most max_extrapolation). Stale (movers_stale),
        each is kept where it was last seen with its reach widening at its last speed: a disc of every place it
        can have got to since (forgotten on a timer, it was driven through)."""
        if not self.known_movers:
            return []
        if not self.movers_stale(t):
            ahead = self.lag(t, self.movers_stamp)
            return [OtherRobot(m.name, (m.position[0] + m.velocity[0] * ahead, m.position[1] + m.velocity[1] * ahead),
                               m.velocity, m.radius, mover=True) for m in self.known_movers]
        since = self.movers_stamp if t - self.movers_stamp >= -self.odom_timeout else self.movers_received
        age = max(t - since, 0.0)
        return [OtherRobot(m.name, m.position, (0.0, 0.0), m.radius + math.hypot(*m.velocity) * age, mover=True)
                for m in self.known_movers]

    def on_scan(self, msg: LaserScan) -> None:
        """Fold a scan into what the robot believes (in lock step: when the planner acts on its time)."""
        if self.locked():
            self.pending_scan = msg
            self.lock_try()
        elif self.planning is not None:
            self.latest_scan = msg   # perceived by the next planning pass, off the control path
        else:
            self.perceive(msg, self.now())

    def perceive(self, msg: LaserScan, t: float, at: float | None = None, state: np.ndarray | None = None,
                 told: Sequence[OtherRobot] | None = None) -> None:
        """Fold a scan into what the robot believes at node time t; the navigator plans in the belief from then on.
        `at`: the time it was taken (lock step: the tick's), else its stamp; `state`: the robot's at t (default: as
        the odometry gives it now)."""
        nav = self.navigator
        if nav is None or self.world is None:
            return   # no map yet: nothing to fuse the scan with
        if state is None:
            state, _ = self.state(t)
        if state is None:
            return   # where the scan was taken from is not known
        stamp = convert.stamp_to_seconds(msg.header.stamp)
        pose = (float(state[0]), float(state[1]), heading(self.model, state))
        if at is None and stamp > 0.0:
            pose = self.pose_at(stamp) or pose   # where the robot was when the scan was taken
        mount, problem = self.scanner_mount(msg.header.frame_id)
        if mount is None:
            self.scan_problem = problem
            self.get_logger().warning(problem, throttle_duration_sec=5.0)
            return
        if mount != frames.IDENTITY:
            pose = frames.compose(pose, mount)   # the scanner's pose: where its beams start, along its zero angle
        if told is None:   # the robots and movers the robot is told of (a planning pass hands its snapshot's)
            told = self.told_others(t)
        try:
            taken = at if at is not None else stamp if stamp > 0.0 else t
            belief = self.scan_perception.update(msg, taken, pose, self.world, told)
        except ValueError as exc:
            self.scan_problem = f'scan ignored: {exc}'
            self.get_logger().warning(self.scan_problem, throttle_duration_sec=5.0)
            return
        # A scanner that cannot see the robot's way (too narrow, too sparse) is used all the same (every return is
        # an obstacle to the guard), and said so on status.
        blind = way_problem(msg.angle_min, msg.angle_max, msg.angle_increment, len(msg.ranges), msg.range_max,
                            mount[2], self.radius)
        self.scan_problem = f'the scan cannot see the robot\'s way: {blind}' if blind else ''
        if blind:
            self.get_logger().warning(self.scan_problem, throttle_duration_sec=60.0)
        nav.guard_check.obstacle_margin = self.scan_perception.margin   # its surfaces are known only that well
        nav.guard_check.scan_points = self.scan_perception.returns      # and the beams' ends are obstacles
        nav.from_scans = True
        if self.planning is not None:
            nav.seen = self.scan_perception.recent.seen()   # where the robot may back up (planning/control.py)
        if belief.world is not nav.world:
            nav.world = belief.world
        self.tracked_pub.publish(convert.belief_to_marker_array(belief, self.stamp(), self.frame_id))

    # ------------------------------------------------------------------------------------------- the state
    def state(self, t: float) -> tuple[np.ndarray | None, str]:
        """The robot's state, or None and why the robot must hold still."""
        if self.odom_problem:
            return None, self.odom_problem
        if self.odom is None:
            return None, f'waiting for odometry on {self.own_odom_topic}'
        if t - self.odom_received > self.odom_timeout:
            return None, f'odometry stale: none for {t - self.odom_received:.2f} s (odom_timeout ' \
                         f'{self.odom_timeout:g} s)'
        if t < self.odom_received - STAMP_EPS:
            # The clock went back since it came (a restarted clock): how old it is is not known.
            return None, f'odometry stale: received at {self.odom_received:.2f} s, after this node\'s clock ' \
                         f'({t:.2f} s): the clock went back'
        if self.model == 'tractor_trailer' and self.trailer is None:
            return None, 'waiting for trailer_pose'
        transform = self.map_to_odom()
        if transform is None:
            source = self.localization_topic or '/tf'
            return None, f'waiting for localization on {source} (map -> {self.odom_frame_id})'
        try:
            state = frames.state_in_frame(transform, convert.pose_to_state(self.odom.pose, self.model, self.trailer))
            self.body_yaw = frames.compose(transform, self.odom.pose)[2]
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

    def scanner_mount(self, frame: str) -> tuple[frames.Pose2D | None, str]:
        """Where a scan in `frame` was taken on the robot: base_link (or no frame) is the reference point; any other
        frame is the scanner's own, mounted at laser_mount; None and why when that is not given."""
        if frame in ('', self.base_frame_id, 'base_link'):
            return frames.IDENTITY, ''
        if self.laser_mount is None:
            return None, (f'scan ignored: its frame {frame!r} is not {self.base_frame_id!r} and parameter laser_mount '
                          f'(where that frame sits in base_link) is not set')
        return self.laser_mount, ''

    def pose_at(self, stamp: float) -> tuple[float, float, float] | None:
        """The robot's map pose (x, y, the scanner's heading) at `stamp`, interpolated from its odometry; None when
        the odometry kept does not reach it (a scan stamped after the newest odometry: the state now is nearer)."""
        odometry, transform = self.map_from_odom.interpolated(stamp), self.map_to_odom()
        if odometry is None or transform is None:
            return None
        x, y, yaw = frames.compose(transform, odometry)
        return x, y, 0.0 if self.model == 'point_mass' else yaw

    def lag(self, t: float, stamp: float) -> float:
        """How far to predict a message stamped `stamp` forward to the control time t (not at all within STAMP_EPS:
        a stamp is whole nanoseconds, a tick's time k * dt is not, and a prediction over 1e-15 s moves a position by
        its last bit)."""
        ahead = t - stamp
        return 0.0 if ahead < STAMP_EPS else min(ahead, self.max_extrapolation)

