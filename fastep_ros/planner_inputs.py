"""What the planner node hears, and the robot's state it makes of it: the world (/obstacles, /map), its robot's
odometry, localization and trailer pose, the movers (/movers) and its own scans.

`PlannerInputs` is PlannerNode's `inputs` member (fastep_ros/planner.py: parameters, goals, lock step, the control
loop): it makes the subscriptions, owns what they bring and the state made of it, and reads the rest of the node
(its navigator, clock, lock step, the other robots) through the node.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Callable, Protocol, Sequence

import numpy as np
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid, Odometry
from rclpy.clock import Clock, ClockType
from rclpy.lifecycle import LifecycleNode
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import LaserScan
from visualization_msgs.msg import MarkerArray

from fastep_core.perception.belief import Belief, heading
from fastep_core.perception.uncertainty import OdometryDrift, PoseUncertainty
from fastep_core.planning.navigator import Navigator
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.safety.guard import ScanReturns
from fastep_core.planning.safety.guard_inputs import GuardInputs
from fastep_core.sensing.laser import way_problem
from fastep_core.world import World
from fastep_ros.common import RepeatedLine, StartupError
from fastep_ros.initial_pose import InitialPose
from fastep_ros.latched import LatchedSubscription
from fastep_ros.limits import LOCALIZATION_EXTENT_MAX, LOCALIZATION_MARGIN, TF_LOCALIZER_INTERVAL
from fastep_ros.live_tf import LOCALIZATION_QOS, TfListener
from fastep_ros.lock_step import STAMP_EPS
from fastep_ros.perception import ScanPerception
from fastep_ros.planner_threads import AdoptWorld, Change, Localized
from fastep_ros.planning_thread import PlanningThread
from fastep_ros.robots import RobotFollower
from fastep_ros.sensors import PlacedScan, ScanSource
from fastep_ros.world_builder import BuiltWorld, WorldBuilder, WorldJob
from msg_tools import convert, frames, interface
from msg_tools.interface import LATEST, offered_qos

__all__ = ['TWIST_CHECKS', 'TWIST_SLACK', 'WORLD_LOG_PERIOD', 'WORLD_POLL', 'Body', 'PlannerInputs',
           'PlannerNodeView']

TWIST_SLACK = 0.2   # m/s: a pose may move this much faster than its odometry's twist says (noise, latency)
TWIST_CHECKS = 3    # odometry messages in a row beyond it: the twist is not the base's velocity
WORLD_LOG_PERIOD = 10.0   # wall s between "world updated" lines (SLAM republishes its map every few seconds) ...
WORLD_POLL = 0.05         # ... and between the executor's looks for a world built off the control path


def _pair(values: dict[str, Any], name: str) -> tuple[float, float]:
    """A parameter of two finite numbers >= 0 (StartupError in one line otherwise)."""
    value = values[name]
    if len(value) != 2 or not all(math.isfinite(v) and v >= 0.0 for v in value):
        raise StartupError(f'parameter {name} must be two finite numbers >= 0, got {list(value)}')
    return float(value[0]), float(value[1])


@dataclass(frozen=True)
class Body:
    """What make_robot needs to know about the robot."""

    model: str
    length: float
    trailer_length: float
    hitch_offset: float


class _StatusPublisher(Protocol):
    def publish(self, force: bool = False, at: float | None = None) -> None: ...
    def changed(self) -> None: ...


class PlannerNodeView(Protocol):
    """What the inputs read of their planner node (fastep_ros.planner.PlannerNode); `ros`: the node itself."""

    frame_id: str
    base_frame_id: str
    model: str
    radius: float
    odom_timeout: float
    max_extrapolation: float
    navigator: Navigator | None
    planning: PlanningThread[Any, Any] | None
    robots: RobotFollower
    tf: TfListener
    last_command: np.ndarray

    @property
    def ros(self) -> LifecycleNode: ...
    @property
    def reports(self) -> _StatusPublisher: ...
    def now(self) -> float: ...
    def locked(self) -> bool: ...
    def stamp(self) -> Any: ...
    def lock_try(self) -> None: ...
    def update_world(self) -> None: ...
    def change(self, request: Change) -> None: ...


class PlannerInputs:
    """What the planner node (fastep_ros.planner.PlannerNode) hears, with the robot's state it makes of it: the
    node's `inputs`. Its handlers are the subscriptions' callbacks; the rest of the node is read through `node`."""

    def __init__(self, node: PlannerNodeView, values: dict[str, Any]) -> None:
        self.node = node
        # What it was built with (the parameters of fastep_ros.planner_params).
        self.obstacle_source: str = values['obstacle_source']
        self.occupied_threshold: int = values['occupied_threshold']
        self.localization_topic: str = values['localization_topic']
        self.map_to_odom_from_tf: bool = values['map_to_odom_from_tf']
        self.odom_frame_id: str = values['odom_frame_id'] or frames.odom_frame(node.ros.get_namespace())
        workspace = values['workspace']
        self.workspace_param: tuple[float, float, float, float] | None = tuple(workspace) if workspace else None
        # Where each scan was taken (laser_mount, else TF) and whether the robot may drive on them: on the executor.
        self.scans = ScanSource(values, node.base_frame_id, interface.SCAN, node.now(),
                                lambda target, source, stamp: node.tf.lookup_at(target, source, stamp))
        # The world: /obstacles and /map.
        self.obstacles: list[Any] | None = None
        self.map_workspace: tuple[float, float, float, float] | None = None
        self.occupied: Callable[[Sequence[float]], bool] | None = None   # obstacle_source map: is a point occupied
        self.world: World | None = None
        # Worlds built off the control path (fastep_ros.world_builder): what came and is not adopted yet (the
        # newest of each), the newest job's number, and why the last message was refused or coarsened.
        self.pending_grid: convert.GridCopy | None = None
        self.pending_markers: MarkerArray | None = None
        self.world_generation = 0
        self.world_problem = ''
        self._world_warned = ''
        self.builder: WorldBuilder | None = None
        self.world_timer: Any = None
        # Worlds may come at any rate (SLAM: every few seconds): their lines at most once a WORLD_LOG_PERIOD.
        self.world_info = RepeatedLine(lambda text: node.ros.get_logger().info(text), WORLD_LOG_PERIOD)
        self.world_warning = RepeatedLine(lambda text: node.ros.get_logger().warning(text), WORLD_LOG_PERIOD)
        self.world_error = RepeatedLine(lambda text: node.ros.get_logger().error(text), WORLD_LOG_PERIOD)
        # The robot's own odometry, localization and trailer pose.
        self.odom: frames.StampedPose | None = None
        self.odom_received = -math.inf
        self.odom_stamp = -math.inf   # its header stamp; when it arrived if that is unset (zero)
        self.odom_problem = ''
        self.odom_heard = 0           # own odometry messages taken
        self.odom_lag = 0.0
        self.twist_problem = ''        # why the odometry's twist is not the base's velocity ('' when it is)
        self._twist_disagrees = 0      # odometry messages in a row whose twist their poses contradict
        self.map_from_odom = frames.MapFromOdom()
        self.localization_problem = ''   # why the last localization pose was ignored ('' when it was taken)
        # Why the map -> odom in use is not the localizer's newest (its newest put the robot off the map; the last
        # one taken is kept): said on status while the robot drives on it ('' when the newest is used).
        self.localization_refused = ''
        self.body_yaw = 0.0   # map-frame heading of base_link at the last state: turns map commands into body ones
        self.trailer: float | None = None
        self.trailer_stamp = -math.inf
        # The known movers of a v2 world (fastep-map's /movers, where the map puts them), avoided and yielded to.
        self.known_movers: list[OtherRobot] = []
        self.movers_stamp = -math.inf
        self.movers_received = -math.inf
        self._stale_logged: list[str] = []   # what stale_inputs last said was stale
        # Scans: perceived (fastep_ros.perception) and the belief shown on `tracked_obstacles`.
        tolerance, drift = (_pair(values, name) for name in ('localization_tolerance', 'odometry_drift'))
        self.localization_sigmas: float = values['localization_sigmas']
        self.scan_perception = ScanPerception(values['scan_noise'], PoseUncertainty(*tolerance), OdometryDrift(*drift))
        self._tf_map_to_odom: frames.Pose2D | None = None   # the last map -> odom TF gave (a new one: localized)
        self._tf_taken: tuple[frames.Pose2D, float] | None = None   # the last one taken (not refused), its stamp
        self.tf_problem = ''   # why map -> odom from TF is not used ('' when it is, or none came)
        self.pending_scan: PlacedScan | None = None   # lock step: the newest scan, perceived when acted on
        self.latest_scan: PlacedScan | None = None    # with the planning thread: perceived by the next pass
        self.seen_problem = ''   # what perception said of the last scan it took ('' when nothing)

    def subscribe(self) -> None:
        """The subscriptions (and the belief's lifecycle publisher), once the node has its own publishers; made by
        the node's configure, destroyed by its cleanup (unsubscribe)."""
        node = self.node
        # Taken as bytes (frames.stamped_pose): once a tick, and an Odometry message costs ~50 us to build.
        self.odom_sub = node.ros.create_subscription(Odometry, interface.ODOM, self.on_odom, LATEST, raw=True)
        self.own_odom_topic: str = self.odom_sub.topic_name
        self.subscriptions: list[Any] = [self.odom_sub]   # the plain ones (world_subs renew their own)
        if node.model == 'tractor_trailer':
            self.subscriptions.append(node.ros.create_subscription(PoseStamped, interface.TRAILER_POSE,
                                                                   self.on_trailer, LATEST))
        # The latched world, subscribed again if a new publisher's message does not come (fastep_ros.latched).
        self.world_subs: list[LatchedSubscription] = []
        if self.obstacle_source == 'markers':
            self.world_subs.append(LatchedSubscription(node.ros, MarkerArray, interface.OBSTACLES, self.on_obstacles,
                                                       offered_qos(interface.OBSTACLES)))
        if self.workspace_param is None or self.obstacle_source == 'map':
            self.world_subs.append(LatchedSubscription(node.ros, OccupancyGrid, interface.MAP, self.on_map,
                                                       offered_qos(interface.MAP)))
        if self.localization_topic:
            # Best available durability: AMCL offers amcl_pose transient-local (then its last pose comes at once);
            # a volatile publisher matches too, without incompatible-QoS warnings.
            sub = node.ros.create_subscription(PoseWithCovarianceStamped, self.localization_topic,
                                               self.on_localization, LOCALIZATION_QOS)
            self.localization_topic = sub.topic_name
            self.subscriptions.append(sub)
        # initialpose (BasicNavigator.setInitialPose, RViz): sets map -> odom where the planner has no localizer.
        self.initial_pose = InitialPose(self)
        self.subscriptions.append(self.initial_pose.sub)
        self.subscriptions.append(node.ros.create_subscription(MarkerArray, interface.MOVERS, self.on_movers, LATEST))
        # Any LaserScan on `scan` (sensor-data QoS: a best-effort subscription matches reliable publishers too):
        # the planner perceives with it (fastep_ros.perception) and shows its belief on `tracked_obstacles`.
        self.scan_sub = None if not self.scans.followed else \
            node.ros.create_subscription(LaserScan, interface.SCAN, self.on_scan, qos_profile_sensor_data)
        if self.scan_sub is not None:
            self.scans.topic = self.scan_sub.topic_name
            self.subscriptions.append(self.scan_sub)
        self.tracked_pub = node.ros.create_lifecycle_publisher(MarkerArray, interface.TRACKED_OBSTACLES, LATEST)

    def unsubscribe(self) -> None:
        """Destroy what subscribe made (the node's cleanup; after a subscribe that failed half-way too)."""
        ros, made = self.node.ros, vars(self)
        builder = made.get('builder')
        if builder is not None:
            builder.stop()   # a build under way ends on its own (a daemon thread), its world unused
            self.builder = None
        if made.get('world_timer') is not None:
            ros.destroy_timer(self.world_timer)
            self.world_timer = None
        for sub in made.get('world_subs', []):
            sub.destroy()
        for each in made.get('subscriptions', []):
            ros.destroy_subscription(each)
        if 'tracked_pub' in made:
            ros.destroy_lifecycle_publisher(self.tracked_pub)
        self.world_subs, self.subscriptions, self.scan_sub = [], [], None

    def movers_stale(self, t: float) -> bool:
        """Whether the known movers are older than odom_timeout (the map node stopped or stalled), or stamped
        further than that ahead of this node's clock."""
        timeout = self.node.odom_timeout
        return bool(self.known_movers) and not (t - self.movers_received <= timeout and
                                                -timeout <= t - self.movers_stamp <= timeout)

    def stale_inputs(self, t: float) -> list[tuple[str, float]]:
        """What this robot avoids on data that stopped coming, and how old that data is: other robots whose
        odometry stopped (by name; fastep_ros.robots), the known movers ('/movers'). Logged when that changes."""
        stale = [(r.name, t - r.received) for r in self.node.robots.fleet.stale(t)]
        if self.movers_stale(t):
            stale.append((interface.MOVERS, t - self.movers_received))
        names = [name for name, _ in stale]
        if names != self._stale_logged:
            went, back = [n for n in names if n not in self._stale_logged], \
                [n for n in self._stale_logged if n not in names]
            if went:
                self.node.ros.get_logger().warning(f'stale: {", ".join(went)}; avoided where last seen, the reach '
                                                   f'widening at the last speed known, until fresh data comes')
            if back:
                self.node.ros.get_logger().info(f'fresh again: {", ".join(back)}')
            self._stale_logged = names
        return stale

    # ------------------------------------------------------------------------------------------- the world
    def on_obstacles(self, msg: MarkerArray) -> None:
        """/obstacles: kept as it came, read into obstacles when the world is built (PlannerNode.update_world)."""
        self.pending_markers = msg
        self.node.update_world()

    def on_map(self, msg: OccupancyGrid) -> None:
        """/map: its workspace at once; with obstacle_source map its cells copied (at most MAX_GRID_CELLS), the walls
        made when the world is built (PlannerNode.update_world). A map that cannot be used is refused, the world
        before kept."""
        try:
            workspace = convert.occupancy_grid_workspace(msg)
            grid = convert.grid_copy(msg) if self.obstacle_source == 'map' else None
        except ValueError as exc:
            self.refused(interface.MAP, str(exc))
            return
        self.map_workspace = workspace
        if grid is not None:
            self.pending_grid = grid
        self.node.update_world()

    def world_job(self) -> WorldJob | None:
        """A job of the newest inputs (a new generation), or None while the world lacks its obstacles or its
        workspace."""
        workspace = self.workspace_param or self.map_workspace
        by_map = self.obstacle_source == 'map'
        pending = self.pending_grid if by_map else self.pending_markers
        if workspace is None or (pending is None and self.obstacles is None):
            return None
        self.world_generation += 1   # a result of an earlier job is dropped: this one has the newest of all
        job = WorldJob(self.world_generation, workspace, interface.MAP if by_map else interface.OBSTACLES,
                       occupied_threshold=self.occupied_threshold)
        if pending is None:   # only the workspace changed
            return dataclasses.replace(job, obstacles=tuple(self.obstacles or ()))
        return dataclasses.replace(job, grid=self.pending_grid) if by_map else \
            dataclasses.replace(job, markers=self.pending_markers)

    def build_later(self, job: WorldJob) -> None:
        """Hand a job to the world builder thread (made at the first); the world timer looks for its result."""
        if self.builder is None:
            self.builder = WorldBuilder(self.node.ros.get_logger().error)
            self.world_timer = self.node.ros.create_timer(WORLD_POLL, self.on_world_timer,
                                                          clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.builder.submit(job)
        self.world_timer.reset()

    def on_world_timer(self) -> None:
        """A world built off the control path taken; the timer off once nothing is being built."""
        builder = self.builder
        if builder is None:
            return
        result = builder.take()
        if result is not None:
            self.take_built(result)
        if not builder.busy:
            self.world_timer.cancel()

    def take_built(self, result: BuiltWorld) -> None:
        """A built world (or its refusal), if it is of the newest job: adopted (PlannerNode.change(AdoptWorld)),
        its obstacles counted in status; a result of an older job is dropped (a newer one is on its way)."""
        if result.generation != self.world_generation:
            return
        self.pending_grid = self.pending_markers = None   # in this job: taken, or refused
        if result.world is None:
            self.refused(result.source, result.problem)
            return
        self.obstacles = list(result.world.obstacle_list)
        if result.occupied is not None:
            self.occupied = result.occupied
        self.world_problem = f'{result.source} {result.problem}' if result.problem else ''
        if self.world_problem and self.world_problem != self._world_warned:
            self.world_warning(self.world_problem)
        self._world_warned = self.world_problem
        self.node.change(AdoptWorld(result.world, len(self.obstacles)))

    def refused(self, topic: str, problem: str) -> None:
        """A world message that cannot be used: said once (status, a line), the world before kept."""
        kept = 'the world before kept' if self.obstacles is not None else 'no world yet'
        self.world_problem = f'{topic} refused: {problem}; {kept}'
        if self.world_problem != self._world_warned:
            self.world_error(self.world_problem)
        self._world_warned = self.world_problem
        self.node.reports.changed()

    # ------------------------------------------------------------------------------------------- inputs
    def on_odom(self, msg: Odometry | bytes) -> None:
        """The robot's own odometry: a message, or its bytes (the subscription's: read with msg_tools.cdr)."""
        try:
            odom = frames.stamped_pose(msg)
            frame, pose, stamp = odom.frame_id, odom.pose, odom.stamp
            if frame not in (self.node.frame_id, self.odom_frame_id):
                raise ValueError(f'frame {frame!r} is neither the map frame {self.node.frame_id!r} nor this '
                                 f'robot\'s odom frame {self.odom_frame_id!r} (parameters frame_id, odom_frame_id)')
        except ValueError as exc:
            self.odom_problem = f'odometry rejected: {exc}'
            self.node.ros.get_logger().warning(self.odom_problem, throttle_duration_sec=5.0)
            return
        now = self.node.now()
        self.check_twist(odom)
        # In lock step odometry is of its stamp's time: the start state (stamped 0) is heard again once time runs.
        self.odom, self.odom_received, self.odom_problem = odom, min(now, stamp) if self.node.locked() else now, ''
        self.odom_stamp = stamp if stamp > 0.0 else self.odom_received
        # Kept in either frame: localization finds the odometry of its stamp in it, a scan the pose of its stamp.
        self.map_from_odom.add_odometry(self.odom_stamp, pose)
        self.odom_heard += 1
        if self.odom_heard == 1:
            self.node.reports.publish(force=True)   # a launcher waits for the odometry path to be up
        self.node.lock_try()

    def on_localization(self, msg: PoseWithCovarianceStamped) -> None:
        """A map pose of base_link: map -> odom = it o inverse(the odometry at its stamp). A pose off the map by more
        than LOCALIZATION_MARGIN is refused (off_map): the last map -> odom taken is kept (none: the robot waits)."""
        try:
            if msg.header.frame_id not in ('', self.node.frame_id):
                raise ValueError(f'frame {msg.header.frame_id!r} is not the map frame {self.node.frame_id!r}')
            pose = frames.odometry_pose(msg)
        except ValueError as exc:
            self.refuse_localization(f'localization pose ignored: {exc}')
            return
        off = self.off_map(pose)
        if off:
            self.refuse_localization(f'localization pose refused: {off}')
            return
        self.localization_problem = self.localization_refused = ''
        stamp = convert.stamp_to_seconds(msg.header.stamp)
        self.map_from_odom.add_localization(stamp if stamp > 0.0 else self.node.now(), pose)
        # Its covariance bounds the pose the scans are placed at, and the odometry's drift starts again from it:
        # perception is the planning side's, so between two passes.
        covariance, sigmas = list(msg.pose.covariance), self.localization_sigmas
        self.node.change(Localized(tuple(covariance), sigmas))

    def refuse_localization(self, problem: str) -> None:
        """A localization pose not used: said (status, a throttled line); the last one taken is kept."""
        changed = problem != self.localization_problem
        self.localization_problem = problem
        self.localization_refused = problem if self.map_from_odom.transform is not None else ''
        self.node.ros.get_logger().warning(problem, throttle_duration_sec=5.0)
        if changed:
            self.node.reports.changed()

    def map_bound(self) -> tuple[float, float, float, float] | None:
        """The map's workspace (xmin, ymin, xmax, ymax) the planner plans in (the workspace parameter, else
        /map's), None before there is one."""
        return self.workspace_param or self.map_workspace

    def off_map(self, pose: Sequence[float]) -> str:
        """Why a map pose of base_link cannot be the robot's: farther than LOCALIZATION_MARGIN outside the map's
        workspace (before any map: farther than LOCALIZATION_EXTENT_MAX from the map frame's origin), or not
        finite; '' when it can."""
        x, y = float(pose[0]), float(pose[1])
        if not (math.isfinite(x) and math.isfinite(y)):
            return f'({x:g}, {y:g}) is not finite'
        bound = self.map_bound()
        if bound is None:
            far = math.hypot(x, y)
            return '' if far <= LOCALIZATION_EXTENT_MAX else \
                f'({x:g}, {y:g}) is {far:g} m from the map frame\'s origin, farther than any map ' \
                f'({LOCALIZATION_EXTENT_MAX:g} m)'
        xmin, ymin, xmax, ymax = bound
        outside = math.hypot(max(xmin - x, 0.0, x - xmax), max(ymin - y, 0.0, y - ymax))
        if outside <= LOCALIZATION_MARGIN:
            return ''
        return f'({x:g}, {y:g}) is outside the map [{xmin:g}, {xmax:g}] x [{ymin:g}, {ymax:g}] by more than ' \
               f'{LOCALIZATION_MARGIN:g} m'

    def map_to_odom(self) -> frames.Pose2D | None:
        """map -> odom of the odometry last taken (None: not known yet, the robot holds still): from the
        localization pose topic, else from TF (map_to_odom_from_tf), else the identity (simulation) or what an
        initial pose set."""
        if self.odom is None or self.odom.frame_id == self.node.frame_id:
            return frames.IDENTITY
        if self.localization_topic:
            return self.map_from_odom.transform
        if self.map_to_odom_from_tf:
            return self.map_to_odom_tf(self.odom.pose)
        set_by_hand = self.map_from_odom.transform   # an initial pose's (fastep_ros.initial_pose), else none
        return frames.IDENTITY if set_by_hand is None else set_by_hand

    def map_to_odom_tf(self, odometry: frames.Pose2D) -> frames.Pose2D | None:
        """map -> odom from TF (None: none usable): refused when, composed with the odometry, it puts base_link off
        the map (off_map; the last one taken is kept), not used when older than transform_tolerance beyond the
        TF_LOCALIZER_INTERVAL a localizer may take between two transforms (it stopped)."""
        found = self.node.tf.lookup_stamped(self.node.frame_id, self.odom_frame_id)
        edge = f'{self.node.frame_id} -> {self.odom_frame_id} from TF'
        self.tf_problem = self.localization_refused = ''
        if found is not None:
            x, y, _ = frames.compose(found[0], odometry)
            off = self.off_map((x, y))
            if off:
                self.tf_problem = f'{self.node.frame_id} -> {self.odom_frame_id} from /tf refused: base_link at {off}'
                self.node.ros.get_logger().warning(self.tf_problem, throttle_duration_sec=10.0)
                found = self._tf_taken
                self.localization_refused = self.tf_problem if found is not None else ''
            else:
                self._tf_taken = found
        transform = None if found is None else found[0]
        age = -math.inf if found is None else self.node.now() - found[1]
        tolerance = self.scans.tolerance
        if age > tolerance + TF_LOCALIZER_INTERVAL:
            # A localizer that stopped (or a neighbour's old word): not where the robot is now.
            self.tf_problem = self.tf_problem or \
                f'{edge} is {age:.1f} s old (transform_tolerance {tolerance:g} s beyond the ' \
                f'{TF_LOCALIZER_INTERVAL:g} s a localizer may take between two)'
            self.localization_refused = ''
            self.node.ros.get_logger().warning(self.tf_problem, throttle_duration_sec=10.0)
            transform = None
        if transform is not None and transform != self._tf_map_to_odom:
            # A localizer's new correction (TF carries no covariance): the odometry's drift starts again.
            self._tf_map_to_odom = transform
            self.node.change(Localized(None, self.localization_sigmas))
        return transform

    def on_trailer(self, msg: PoseStamped) -> None:
        try:
            self.trailer = convert.trailer_yaw(msg)
        except ValueError as exc:
            self.odom_problem = f'trailer pose rejected: {exc}'
            self.node.ros.get_logger().warning(self.odom_problem, throttle_duration_sec=5.0)
            return
        self.trailer_stamp = convert.stamp_to_seconds(msg.header.stamp)
        self.node.lock_try()

    def other_robots(self, t: float) -> list[OtherRobot]:
        """The other robots (their odometry), the known movers (/movers) and the movers this robot's scans track."""
        return [*self.told_others(t), *self.scan_perception.movers(t)]

    def told_others(self, t: float) -> list[OtherRobot]:
        """The other robots (their odometry) and the known movers (/movers): what the robot is told of."""
        robots = self.node.robots.fleet.obstacles(t, self.node.robots.radius, lambda stamp: self.lag(t, stamp))
        return [*robots, *self.movers_at(t)]

    def on_movers(self, msg: MarkerArray) -> None:
        try:
            movers = convert.marker_array_to_movers(msg)
        except ValueError as exc:
            self.node.ros.get_logger().warning(f'ignoring /movers: {exc}', throttle_duration_sec=5.0)
            return
        # Every marker after the leading DELETEALL carries the map node's stamp; unset: when it came.
        stamp = convert.stamp_to_seconds(msg.markers[1].header.stamp) if len(msg.markers) > 1 else 0.0
        self.known_movers = movers
        self.movers_received = self.node.now()
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
        since = self.movers_stamp if t - self.movers_stamp >= -self.node.odom_timeout else self.movers_received
        age = max(t - since, 0.0)
        return [OtherRobot(m.name, m.position, (0.0, 0.0), m.radius + math.hypot(*m.velocity) * age, mover=True)
                for m in self.known_movers]

    @property
    def laser_mount(self) -> frames.Pose2D | None:
        return self.scans.laser_mount

    @property
    def scan_problem(self) -> str:
        """Why the last scan was not used (or waits), or what perception said of it ('' when nothing)."""
        return self.scans.problem or self.scans.waiting or self.seen_problem

    def on_scan(self, msg: LaserScan) -> None:
        """A scan: placed on the robot (fastep_ros.sensors, here on the executor), then folded into what the robot
        believes (in lock step: when the planner acts on its time; with the planning thread: by its next pass)."""
        placed = self.scans.take(msg, self.node.now())
        if placed is None:
            if self.scans.problem:
                self.node.ros.get_logger().warning(self.scans.problem, throttle_duration_sec=5.0)
            return
        self.use_scan(placed)

    def retry_scans(self, t: float) -> None:
        """Control tick (lock step: its try): a scan that waited for its transform, used once it has come."""
        if self.scans.pending:
            placed = self.scans.retry(t)
            if placed is not None:
                self.use_scan(placed, act=False)
            elif self.scans.problem and not self.scans.pending:
                self.node.ros.get_logger().warning(self.scans.problem, throttle_duration_sec=5.0)

    def use_scan(self, placed: PlacedScan, act: bool = True) -> None:
        """A placed scan to perception; `act`: in lock step, try to act on its time now."""
        if self.node.locked():
            self.pending_scan = placed
            if act:
                self.node.lock_try()
        elif self.node.planning is not None:
            self.latest_scan = placed   # perceived by the next planning pass, off the control path
        else:
            belief = self.perceive(self.where(placed), self.node.now())
            if belief is not None:
                self.show_belief(belief)

    def where(self, placed: PlacedScan) -> PlacedScan:
        """The scan with the robot's map pose at its stamp (executor: the odometry and TF are read here)."""
        stamp = placed.stamp
        return placed.at(self.pose_at(stamp)) if stamp > 0.0 else placed

    def perceive(self, placed: PlacedScan, t: float, at: float | None = None, state: np.ndarray | None = None,
                 told: Sequence[OtherRobot] | None = None) -> Belief | None:
        """Fold a placed scan into what the robot believes at node time t; the navigator plans in the belief from
        then on, its guards check the scan's returns at once. `at`: the time it was taken (lock step: the tick's),
        else its stamp; `state`: the robot's at t (default: as the odometry gives it now). Returns the belief, for
        the executor to show (show_belief; None: the scan was not perceived). May run on the planning thread: it
        reads only what it is handed and the planning side's own state (perception, the navigator; TF and odometry
        were read when the scan was placed, `where`), and publishes nothing."""
        nav = self.node.navigator
        if nav is None or self.world is None:
            return None   # no map yet: nothing to fuse the scan with
        if state is None:
            state, _ = self.state(t)
        if state is None:
            return None   # where the scan was taken from is not known
        msg, mount = placed.msg, placed.mount
        stamp = placed.stamp
        pose = (float(state[0]), float(state[1]), heading(self.node.model, state))
        if at is None and stamp > 0.0:
            pose = placed.robot_pose or pose   # where the robot was when the scan was taken
        if mount != frames.IDENTITY:
            pose = frames.compose(pose, mount)   # the scanner's pose: where its beams start, along its zero angle
        if told is None:   # the robots and movers the robot is told of (a planning pass hands its snapshot's)
            told = self.told_others(t)
        try:
            taken = at if at is not None else stamp if stamp > 0.0 else t
            belief = self.scan_perception.update(msg, taken, pose, self.world, told)
        except ValueError as exc:
            self.seen_problem = f'scan ignored: {exc}'
            self.node.ros.get_logger().warning(self.seen_problem, throttle_duration_sec=5.0)
            return None
        # A scanner that cannot see the robot's way (too narrow, too sparse) is used all the same (every return is
        # an obstacle to the guard), and said so on status.
        blind = way_problem(msg.angle_min, msg.angle_max, msg.angle_increment, len(msg.ranges), msg.range_max,
                            mount[2], self.node.radius)
        self.seen_problem = f'the scan cannot see the robot\'s way: {blind}' if blind else ''
        if blind:
            self.node.ros.get_logger().warning(self.seen_problem, throttle_duration_sec=60.0)
        # Its surfaces are known only to the margin, the beams' ends are obstacles and, with a control loop of its own
        # (the planning thread), the robot backs up only where recent scans saw free space: one value, together.
        seen = None if self.node.planning is None else self.scan_perception.recent.seen()
        nav.take_perception(GuardInputs(self.scan_perception.margin,
                                        ScanReturns(self.scan_perception.returns, state, nav.radius), seen,
                                        taken),
                            belief.world)
        return belief

    def show_belief(self, belief: Belief) -> None:
        """The belief on `tracked_obstacles` (the executor's: publishers are)."""
        self.tracked_pub.publish(self.belief_markers(belief))

    def belief_markers(self, belief: Belief) -> MarkerArray:
        """What `tracked_obstacles` shows of a belief (stamped now)."""
        return convert.belief_to_marker_array(belief, self.node.stamp(), self.node.frame_id)

    # ------------------------------------------------------------------------------------------- the state
    def state(self, t: float) -> tuple[np.ndarray | None, str]:
        """The robot's state, or None and why the robot must hold still."""
        if self.odom_problem:
            return None, self.odom_problem
        if self.odom is None:
            return None, f'waiting for odometry on {self.own_odom_topic}'
        if t - self.odom_received > self.node.odom_timeout:
            return None, f'odometry stale: none for {t - self.odom_received:.2f} s (odom_timeout ' \
                         f'{self.node.odom_timeout:g} s)'
        if t < self.odom_received - STAMP_EPS:
            # The clock went back since it came (a restarted clock): how old it is is not known.
            return None, f'odometry stale: received at {self.odom_received:.2f} s, after this node\'s clock ' \
                         f'({t:.2f} s): the clock went back'
        if self.node.model == 'tractor_trailer' and self.trailer is None:
            return None, 'waiting for trailer_pose'
        transform = self.map_to_odom()
        if transform is None:
            source = self.localization_topic or '/tf'
            problem = self.localization_problem or self.tf_problem
            why = f': {problem}' if problem else ''
            return None, f'waiting for localization on {source} (map -> {self.odom_frame_id}){why}'
        try:
            state = frames.state_in_frame(transform, convert.pose_to_state(self.odom.pose, self.node.model,
                                                                           self.trailer))
            self.body_yaw = frames.compose(transform, self.odom.pose)[2]
        except ValueError as exc:
            return None, f'odometry rejected: {exc}'
        self.odom_lag = t - self.odom_stamp
        if self.odom_lag < -self.node.odom_timeout:
            # From a clock that ran ahead of this node's (a restarted plant, a clock jump): acting on it would
            # take a position the robot has left for its present one.
            return None, (f'odometry stale: stamped {-self.odom_lag:.2f} s ahead of this node\'s clock '
                          f'(odom_timeout {self.node.odom_timeout:g} s)')
        if self.node.max_extrapolation > 0.0 and self.odom_lag > self.node.max_extrapolation:
            # Where the robot is now cannot be predicted that far: a command from this state would be checked (by
            # the guard) at a position the robot has left.
            return None, (f'odometry stale: stamped {self.odom_lag:.2f} s ago, beyond what it is predicted over '
                          f'(max_extrapolation {self.node.max_extrapolation:g} s)')
        lag = self.lag(t, self.odom_stamp)
        if lag > 0.0 and self.node.navigator is not None:
            # Latency compensation: the plant has applied the last command since the odometry was stamped.
            state = self.node.navigator.model.integrate(state, self.node.last_command, lag)
        return state, ''

    def odometry_state(self) -> np.ndarray | None:
        """The state of the odometry `state` last took, in its own frame, at its stamp: measured, not predicted
        forward (what shows the base sliding where the twist does not: BaseResponse.slide)."""
        if self.odom is None:
            return None
        try:
            return convert.pose_to_state(self.odom.pose, self.node.model, self.trailer)
        except ValueError:
            return None

    def check_twist(self, odom: frames.StampedPose) -> None:
        """Does a new odometry's twist agree with how far its pose moved since the last one? A driver that leaves
        the twist zero (or wrong) would make the closed loop hold the robot to a creep: after TWIST_CHECKS messages
        in a row whose poses moved more than TWIST_SLACK faster than their twists say, the twist is not used and
        status says so (`twist_problem`)."""
        last = self.odom
        if last is None or odom.frame_id != last.frame_id or not odom.stamp > last.stamp:
            return
        dt = odom.stamp - last.stamp
        moved = math.hypot(odom.pose[0] - last.pose[0], odom.pose[1] - last.pose[1]) / dt
        said = math.hypot(odom.twist[0], odom.twist[1])
        if not math.isfinite(said):
            return
        self._twist_disagrees = self._twist_disagrees + 1 if moved > said + TWIST_SLACK else 0
        if self._twist_disagrees >= TWIST_CHECKS and not self.twist_problem:
            self.twist_problem = (f'odometry twist {said:.2f} m/s while its pose moves at {moved:.2f} m/s: not used '
                                  f'(commands ramp from the last command, stops from the configured limits)')
            self.node.ros.get_logger().warning(self.twist_problem)
        elif self._twist_disagrees == 0 and self.twist_problem:
            self.twist_problem = ''
            self.node.ros.get_logger().info('odometry twist agrees with its pose again: used')

    def velocity(self) -> np.ndarray | None:
        """What the base measurably does, from the odometry `state` last took (its twist, in the model's command form:
        a point mass's (vx, vy) turned into the map frame, a diff_drive's (v, omega)); None where it is not
        known (no odometry, a twist that is not finite or that its poses contradict, a tractor-trailer, whose
        twist is not its command)."""
        if self.odom is None or self.node.model == 'tractor_trailer' or self.twist_problem:
            return None
        x, y, z = self.odom.twist
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
            return None
        if self.node.model == 'point_mass':
            if self.body_yaw == 0.0:
                return np.array([x, y])
            c, s = math.cos(self.body_yaw), math.sin(self.body_yaw)
            return np.array([c * x - s * y, s * x + c * y])
        return np.array([x, z])

    def pose_at(self, stamp: float) -> tuple[float, float, float] | None:
        """The robot's map pose (x, y, the scanner's heading) at `stamp`, interpolated from its odometry; None when
        the odometry kept does not reach it (a scan stamped after the newest odometry: the state now is nearer)."""
        odometry, transform = self.map_from_odom.interpolated(stamp), self.map_to_odom()
        if odometry is None or transform is None:
            return None
        x, y, yaw = frames.compose(transform, odometry)
        return x, y, 0.0 if self.node.model == 'point_mass' else yaw

    def lag(self, t: float, stamp: float) -> float:
        """How far to predict a message stamped `stamp` forward to the control time t (not at all within STAMP_EPS:
        a stamp is whole nanoseconds, a tick's time k * dt is not, and a prediction over 1e-15 s moves a position by
        its last bit)."""
        ahead = t - stamp
        return 0.0 if ahead < STAMP_EPS else min(ahead, self.node.max_extrapolation)

