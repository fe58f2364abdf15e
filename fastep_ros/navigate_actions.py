"""Nav2's navigation actions, served by the planner: `navigate_to_pose`, `navigate_through_poses`, `follow_waypoints`,
and controller_server's `follow_path`.

nav2_msgs/action/NavigateToPose, NavigateThroughPoses and FollowWaypoints with Nav2 Jazzy's definitions, in the
planner's namespace, so that a client written for Nav2 (nav2_simple_commander's BasicNavigator, RViz's Nav2
panel) commands a fastep robot unchanged. As in Nav2: goals are accepted only while the node is active; a new
goal preempts the one under way (ABORTED, "preempted by a new goal", error code 0 as Nav2's SimpleActionServer
gives it); feedback comes every FEEDBACK_PERIOD wall
seconds, its distance_remaining along the route the robot follows (fastep_ros.progress.Way, frozen by each pass);
the result is SUCCEEDED, ABORTED with one of Nav2's error codes (ERROR_CODES) and the planner's reason (207 when
planning left no plan for planning_timeout: every goal ends), or CANCELED (the robot brakes to a stop).
follow_waypoints follows Nav2's waypoint follower (goal_index, number_of_loops, missed waypoints,
`stop_on_failure`, false by default as in Nav2's stock params; the goal's own code 0 as Nav2's, the missed
waypoints carrying theirs). A goal in a frame TF cannot put in the map frame ends ABORTED with 0, as Nav2's
navigators give it. Behaviour in full: docs/robots_and_goals.md.

follow_path (nav2_msgs/FollowPath: fastep as the controller of a stack that keeps Nav2's planner) is a run like
navigate_through_poses: the path is put in the map frame and checked at once (GivenPath), simplified to the
poses where it bends (PATH_TOLERANCE), and those are handed to the planner one after another, each a little
before the robot reaches it (PASS_DISTANCE), so that the robot follows the path's shape without stopping on the
way; feedback distance_to_goal is the path left from the robot's projection on it. A new follow_path goal while
one runs is a path update, as in Nav2's controller_server: the old goal ends (ABORTED, 0) and the robot drives
on. FollowPath's error codes: FOLLOW_PATH_CODES.

A goal's poses are bounded (fastep_ros.limits.GOAL_POSES_MAX) and checked all at once when it comes, before the
robot moves (GoalPoses: frames, finite, inside the map, clear of obstacles and occupied cells): one refused pose
ends a navigate_through_poses goal at once; follow_waypoints misses it (stop_on_failure false, in a loop, never
recursing) or ends (true). An ended goal stays with its server ACTION_RESULT_TIMEOUT (wall) seconds, not rclpy's 900.

A goal on the `goal_pose` topic goes the same way (the planner's take_goal) and preempts an action goal under
way. Without nav2_msgs the planner runs without these servers and says so once.

The servers are on a node of their own, `<planner node name>_navigation` (`planner_navigation` by default) in the
planner's namespace, spun on a thread of its own (fastep_ros/action_thread.py): rclpy converts a goal's request
into Python messages where the server's node spins, and 100,000 poses converted on the planner's executor stopped
cmd_vel for seconds. That thread only receives: a goal request is accepted there while the planner is active, a
cancel request accepted, and a goal to execute handed over (ActionGoal, fastep_ros/planner_threads.py). Checking
the poses, driving, feedback and the result stay on the planner's executor, which takes the goals handed over on
every control tick (`check`), publishes feedback, and ends a goal by setting its Future to the terminal state
and result, which the action thread then makes and sends. Made in configure, with the planner's other entities,
and joined and destroyed in cleanup, shutdown and destroy_node (`destroy`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np
from geometry_msgs.msg import PoseStamped
from numpy.typing import NDArray

from fastep_ros.common import shown
from fastep_ros.companion import PREEMPTED, Companion
from fastep_ros.limits import ACTION_RESULT_TIMEOUT, GOAL_POSES_MAX
from fastep_ros.progress import Way, eta

__all__ = ['ERROR_CODES', 'FEEDBACK_PERIOD', 'FOLLOW_PATH_CODES', 'GivenPath', 'GoalPoses', 'NavigateActions',
           'error_code', 'follow_path_code', 'navigation_code', 'simplified']

FEEDBACK_PERIOD = 0.1   # wall seconds between feedback messages (Nav2's navigator sends one per tree tick)
HELD_TIME = 2.0    # s: the ETA's speed is the speed held, smoothed over this long (Nav2's: the odometry's, smoothed)
HELD_LEAST = 0.2   # of the speed it can hold: the least the ETA takes (a turn in place is not a stop)
WAY_WAIT = 1.0          # node seconds feedback waits for a pass to plan the way to a new pose (then: the straight run)

# Nav2 Jazzy's error codes (nav2_msgs ComputePathToPose and FollowPath), by what the planner's reason says.
ERROR_CODES: tuple[tuple[str, int], ...] = (
    ('no valid path', 208),            # ComputePathToPose.NO_VALID_PATH
    ('occupied', 206),                 # GOAL_OCCUPIED
    ('inside an obstacle', 206),
    ('outside the map', 204),          # GOAL_OUTSIDE_MAP
    ('frame', 202),                    # TF_ERROR
    ('failed to make progress', 105),  # FollowPath.FAILED_TO_MAKE_PROGRESS
    ('planning timed out', 207),       # ComputePathToPose.TIMEOUT: no plan for planning_timeout
)
UNKNOWN_PLANNING = 200   # ComputePathToPose.UNKNOWN: a goal the planner refused for another reason
UNKNOWN_DRIVING = 100    # FollowPath.UNKNOWN: stopped on the way for another reason


def error_code(reason: str, refused: bool = False) -> int:
    """Nav2's error code for a planner's failure reason."""
    for words, code in ERROR_CODES:
        if words in reason:
            return code
    return UNKNOWN_PLANNING if refused else UNKNOWN_DRIVING


TO_POSE, THROUGH_POSES, WAYPOINTS = 'navigate_to_pose', 'navigate_through_poses', 'follow_waypoints'
FOLLOW_PATH = 'follow_path'
TASK_EXECUTOR_FAILED = 601   # FollowWaypoints: a task at a waypoint failed (fastep runs none: never given)
GOAL_OCCUPIED, GOAL_OUTSIDE_MAP, TF_ERROR = 206, 204, 202   # ComputePathToPose, as ERROR_CODES gives them
# What a Nav2 client sees, where Nav2 Jazzy fills no error code (nav2_util's SimpleActionServer ends a goal with an
# empty result: error_code 0, error_msg ''): fastep says why in error_msg, with 0.
WAYPOINTS_FAILED = 0    # waypoint_follower: terminate_current(result), its error_code never set (stop_on_failure)
NAVIGATION_TF = 0       # bt_navigator: a goal pose TF cannot transform, goalReceived false, terminate_current()

# nav2_msgs FollowPath (Jazzy) result codes, by what the planner's reason or the path check says.
FP_UNKNOWN, FP_TF_ERROR, FP_INVALID_PATH = 100, 102, 103
FP_FAILED_TO_MAKE_PROGRESS, FP_NO_VALID_CONTROL = 105, 106
FOLLOW_PATH_CODES: tuple[tuple[str, int], ...] = (
    ('no valid path', FP_NO_VALID_CONTROL),          # the path blocked: no way on to the pose driven to
    ('occupied', FP_NO_VALID_CONTROL),
    ('inside an obstacle', FP_NO_VALID_CONTROL),
    ('outside the map', FP_INVALID_PATH),
    ('frame', FP_TF_ERROR),
    ('failed to make progress', FP_FAILED_TO_MAKE_PROGRESS),
    ('planning timed out', FP_FAILED_TO_MAKE_PROGRESS),   # no control for planning_timeout: what Nav2's progress
)                                                         # checker ends
PATH_POSES_MAX = 10 * GOAL_POSES_MAX   # a follow_path path may have more poses (Nav2's: one every 5 cm; 1 km)
PATH_TOLERANCE = 0.05   # m: the poses driven through stay this close to the path given (Douglas-Peucker): the
#                         bends kept, a grid planner's 5 cm steps not (each would be a pose to aim for)
PASS_DISTANCE = 0.3     # m: a pose on the way is passed (the next one handed over) this close, along the path or
#                         straight: before goal_tolerance would make the planner stop there (at least twice that)
TRACK_BACK, TRACK_AHEAD = 0.5, 2.0   # m: the robot is looked for on the path this far behind / ahead of where it
#                                       was (a path that comes back near itself is not jumped along)
TRACK_SNAP = 0.25       # m: a new path's first projection: the earliest part of the path within this of the nearest


def follow_path_code(reason: str) -> int:
    """FollowPath's error code for a planner's failure reason."""
    for words, code in FOLLOW_PATH_CODES:
        if words in reason:
            return code
    return FP_UNKNOWN


def navigation_code(code: int) -> int:
    """The code Nav2's navigators give for one of ERROR_CODES: TF_ERROR is ComputePathToPose's (planner_server's),
    which bt_navigator never sends (a goal it cannot transform ends with 0)."""
    return NAVIGATION_TF if code == TF_ERROR else code
CLEARANCE_PAIRS = 1_000_000   # pose-obstacle distances computed at a time (memory: 8 MB a chunk)
ACTION_JOIN = 10.0            # wall seconds destroy waits for the action thread (a request under conversion)


class GoalPoses:
    """A goal's poses, in the map frame and checked, all at once when the goal comes: what the run drives through.

    `codes[i]` is 0 for a pose the planner can take as the world is known now, else Nav2's error code for why not,
    checked as PlannerNode.goal_problem checks one goal (frame, heading, finite, inside the map, clear of every
    obstacle by the robot's radius, not in an occupied cell of /map). A pose in another frame is put in the map
    frame through TF now (as Nav2's navigate_through_poses does when its goal comes). `after[i]`: the length of
    the legs from pose i through the later ones to the last (feedback's distance_remaining in O(1) a tick).
    """

    def __init__(self, node: Any, given: Sequence[PoseStamped]) -> None:
        self.node = node
        self.given = list(given)
        n = len(self.given)
        frames = [p.header.frame_id.lstrip('/') for p in self.given]
        xy = np.array([(p.pose.position.x, p.pose.position.y) for p in self.given], dtype=float).reshape(n, 2)
        quat = np.array([(p.pose.orientation.x, p.pose.orientation.y, p.pose.orientation.z, p.pose.orientation.w)
                         for p in self.given], dtype=float).reshape(n, 4)
        self.codes: NDArray[np.int64] = np.zeros(n, dtype=np.int64)
        self.moved: NDArray[np.bool_] = np.zeros(n, dtype=bool)   # put in the map frame through TF
        with np.errstate(invalid='ignore'):
            norm2 = (quat * quat).sum(axis=1)
            has_heading = norm2 > 0.0
            yaw = np.arctan2(2.0 * (quat[:, 3] * quat[:, 2] + quat[:, 0] * quat[:, 1]),
                             1.0 - 2.0 * (quat[:, 1] ** 2 + quat[:, 2] ** 2))
        self.yaw = np.where(has_heading, yaw, np.nan)   # in the map frame once moved; NaN: none asked for
        for frame in set(frames) - {'', 'map', node.frame_id}:
            mask = np.array([f == frame for f in frames])
            pose = node.tf.lookup(node.frame_id, frame)
            if pose is None:
                self.codes[mask] = TF_ERROR
                continue
            c, s = math.cos(pose[2]), math.sin(pose[2])
            x, y = xy[mask, 0], xy[mask, 1]
            xy[mask] = np.column_stack([pose[0] + c * x - s * y, pose[1] + s * x + c * y])
            self.yaw[mask] = np.angle(np.exp(1j * (self.yaw[mask] + pose[2])))   # wrapped; NaN stays NaN
            self.moved |= mask
        self.xy = xy
        if node.model == 'diff_drive':   # the only model a goal's heading is asked of (goal_heading_of)
            self._refuse(~np.isfinite(quat).all(axis=1), UNKNOWN_PLANNING)
        self._refuse(~np.isfinite(xy).all(axis=1), UNKNOWN_PLANNING)
        nav = node.navigator
        if nav is not None:
            xmin, ymin, xmax, ymax = nav.world.workspace
            with np.errstate(invalid='ignore'):
                inside = (xmin <= xy[:, 0]) & (xy[:, 0] <= xmax) & (ymin <= xy[:, 1]) & (xy[:, 1] <= ymax)
            self._refuse(~inside, GOAL_OUTSIDE_MAP)
            obstacles = nav.world.obstacles
            left = np.flatnonzero(self.codes == 0)
            if len(obstacles) and len(left):
                step = max(1, CLEARANCE_PAIRS // len(obstacles))
                clearance = np.concatenate([obstacles.clearance(xy[left[i:i + step]])
                                            for i in range(0, len(left), step)])
                self.codes[left[clearance < nav.radius]] = GOAL_OCCUPIED
        occupied = node.inputs.occupied
        if occupied is not None:
            # One lookup a pose (the grid's lookup takes one point), over at most GOAL_POSES_MAX poses.
            left = np.flatnonzero(self.codes == 0)
            cells = np.array([bool(occupied(xy[i])) for i in left], dtype=bool)
            self.codes[left[cells]] = GOAL_OCCUPIED
        legs = np.hypot(*np.diff(np.nan_to_num(xy), axis=0).T) if n > 1 else np.zeros(0)
        self.after: NDArray[np.float64] = np.concatenate([np.cumsum(legs[::-1])[::-1], [0.0]])

    def _refuse(self, where: Any, code: int) -> None:
        """Those of `where` not refused yet are refused with `code` (the first reason, as goal_problem's order)."""
        self.codes[np.asarray(where, dtype=bool) & (self.codes == 0)] = code

    def __len__(self) -> int:
        return len(self.given)

    def refused(self) -> NDArray[np.intp]:
        """Indices of the poses refused, in order."""
        return np.flatnonzero(self.codes)

    def msg(self, i: int) -> PoseStamped:
        """Pose i in the map frame: as given there, or a new message put there when the goal came."""
        given = self.given[i]
        if not self.moved[i]:
            return given
        out = PoseStamped()
        out.header.stamp, out.header.frame_id = given.header.stamp, self.node.frame_id
        out.pose.position.x, out.pose.position.y = float(self.xy[i, 0]), float(self.xy[i, 1])
        yaw = float(self.yaw[i])
        if math.isfinite(yaw):
            out.pose.orientation.z, out.pose.orientation.w = math.sin(0.5 * yaw), math.cos(0.5 * yaw)
        else:
            out.pose.orientation.w = 0.0   # a quaternion of zero length: no heading asked for, as given
        return out

    def problem(self, i: int) -> str:
        """Why pose i was refused, in the words the planner's goal check uses."""
        if self.codes[i] == TF_ERROR:
            return self.node.goal_in_map(self.given[i])[1] or 'goal frame: no transform'
        x, y = self.xy[i]
        what = 'orientation is not finite' if math.isfinite(x) and math.isfinite(y) else 'is not finite'
        return self.node.goal_problem(self.msg(i)) or f'goal ({x}, {y}) {what}'


def simplified(xy: NDArray[np.float64], tolerance: float) -> NDArray[np.intp]:
    """Indices of the points of the polyline `xy` that a polyline within `tolerance` of every point keeps
    (Douglas-Peucker: the first and last, then the farthest from the chord of each span until none is farther),
    in order. A loop over the spans split, each measured vectorised: O(points x kept)."""
    n = len(xy)
    if n <= 2:
        return np.arange(n)
    keep = np.zeros(n, dtype=bool)
    keep[[0, n - 1]] = True
    spans = [(0, n - 1)]
    while spans:
        i, j = spans.pop()
        if j - i < 2:
            continue
        a, chord = xy[i], xy[j] - xy[i]
        inner = xy[i + 1:j] - a
        length = math.hypot(*chord)
        if length > 0.0:   # the distance to the segment i-j (the chord's ends for points beyond them)
            t = np.clip(inner @ chord / (length * length), 0.0, 1.0)
            off = np.hypot(*(inner - t[:, None] * chord).T)
        else:              # a path that comes back to where the span began
            off = np.hypot(*inner.T)
        k = int(np.argmax(off))
        if off[k] > tolerance:
            m = i + 1 + k
            keep[m] = True
            spans += [(i, m), (m, j)]
    return np.flatnonzero(keep)


def path_points(poses: Sequence[PoseStamped]) -> NDArray[np.float64]:
    """The positions of a path's poses, (n, 2): Python objects read one by one (20,000 poses: about 20 ms)."""
    return np.array([(p.pose.position.x, p.pose.position.y) for p in poses], dtype=float).reshape(len(poses), 2)


class GivenPath:
    """A follow_path goal's path (nav_msgs/Path), in the map frame and checked, all at once when it comes, and where
    the robot is along it.

    The path's frame is its header's (Nav2's controller_server reads no other; the first pose's when the header
    has none), put in the map frame through TF now. `code` is 0 for a path that can be driven, else FollowPath's
    error code, with `problem` saying why: INVALID_PATH (empty, more than PATH_POSES_MAX poses, a pose not finite
    or outside the map), TF_ERROR (a frame TF does not reach), NO_VALID_CONTROL (its last pose inside an obstacle
    or an occupied cell). `targets`: the poses handed to the planner in turn, the path simplified to PATH_TOLERANCE
    (simplified), the first left out (where the path starts: the robot), the last with the heading given; one
    refused on the way (within the robot's radius of an obstacle) is left out, the planner's route going round it.
    `along`: the path's length from its start to each pose; `at`: the robot's projection on it (`locate`)."""

    def __init__(self, node: Any, path: Any, points: NDArray[np.float64] | None = None) -> None:
        """`points`: the poses' positions as given (path_points), read already on the action thread; None: read
        here."""
        self.node = node
        self.code, self.problem = 0, ''
        self.xy: NDArray[np.float64] = np.zeros((0, 2))
        self.along: NDArray[np.float64] = np.zeros(0)
        self.targets: list[PoseStamped] = []
        self.target_along: NDArray[np.float64] = np.zeros(0)
        self.skipped = 0      # poses on the way refused (left out of the targets)
        self.at = math.nan    # the robot's projection: its length along the path (NaN: not located yet)
        self.passing = max(PASS_DISTANCE, 2.0 * float(node.params.goal_tolerance))
        poses = path.poses
        n = len(poses)
        if n == 0:
            self._refuse(FP_INVALID_PATH, 'the path is empty')
            return
        if n > PATH_POSES_MAX:
            self._refuse(FP_INVALID_PATH, f'{n} poses, more than the {PATH_POSES_MAX} a path may have')
            return
        frame = (path.header.frame_id or poses[0].header.frame_id).lstrip('/')
        xy = path_points(poses) if points is None or len(points) != n else points
        last = poses[-1].pose.orientation
        quat = np.array([last.x, last.y, last.z, last.w], dtype=float)
        bad = np.flatnonzero(~np.isfinite(xy).all(axis=1))
        if len(bad):
            self._refuse(FP_INVALID_PATH, f'path pose {int(bad[0])} is not finite ({len(bad)} of {n})')
            return
        yaw = math.nan   # the last pose's heading in the map frame (NaN: none asked for)
        if np.isfinite(quat).all() and float(quat @ quat) > 0.0:
            yaw = math.atan2(2.0 * (quat[3] * quat[2] + quat[0] * quat[1]), 1.0 - 2.0 * (quat[1] ** 2 + quat[2] ** 2))
        elif node.model == 'diff_drive' and not np.isfinite(quat).all():
            self._refuse(FP_INVALID_PATH, f'path pose {n - 1}: orientation is not finite')
            return
        if frame not in ('', 'map', node.frame_id):
            pose = node.tf.lookup(node.frame_id, frame)
            if pose is None:
                self._refuse(FP_TF_ERROR, f'path frame {shown(frame)}: no transform to {node.frame_id!r} on /tf '
                             'or /tf_static')
                return
            c, s = math.cos(pose[2]), math.sin(pose[2])
            xy = np.column_stack([pose[0] + c * xy[:, 0] - s * xy[:, 1], pose[1] + s * xy[:, 0] + c * xy[:, 1]])
            yaw = yaw + pose[2]   # NaN stays NaN
        nav = node.navigator
        if nav is not None:
            xmin, ymin, xmax, ymax = nav.world.workspace
            outside = np.flatnonzero((xy[:, 0] < xmin) | (xy[:, 0] > xmax) | (xy[:, 1] < ymin) | (xy[:, 1] > ymax))
            if len(outside):
                i = int(outside[0])
                self._refuse(FP_INVALID_PATH, f'path pose {i} ({xy[i, 0]:g}, {xy[i, 1]:g}) is outside the map')
                return
        self.xy = xy
        self.along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
        kept = simplified(xy, PATH_TOLERANCE)
        kept = kept[1:] if len(kept) > 1 else kept
        msgs = [self._pose(i, yaw if i == n - 1 else math.nan, path.header.stamp) for i in kept]
        checked = GoalPoses(node, msgs)
        if checked.codes[-1]:   # the path's end in an obstacle or an occupied cell: blocked
            self._refuse(FP_NO_VALID_CONTROL, f'its last pose: {checked.problem(len(msgs) - 1)}')
            return
        usable = checked.codes == 0
        self.skipped = int((~usable).sum())
        self.targets = [m for m, ok in zip(msgs, usable) if ok]
        self.target_along = self.along[kept[usable]]

    def _refuse(self, code: int, problem: str) -> None:
        self.code, self.problem = code, problem

    def _pose(self, i: int, yaw: float, stamp: Any) -> PoseStamped:
        """Path pose i in the map frame, with `yaw` (NaN: no heading, a quaternion of zero length)."""
        out = PoseStamped()
        out.header.stamp, out.header.frame_id = stamp, self.node.frame_id
        out.pose.position.x, out.pose.position.y = float(self.xy[i, 0]), float(self.xy[i, 1])
        if math.isfinite(yaw):
            out.pose.orientation.z, out.pose.orientation.w = math.sin(0.5 * yaw), math.cos(0.5 * yaw)
        else:
            out.pose.orientation.w = 0.0
        return out

    @property
    def length(self) -> float:
        return float(self.along[-1]) if len(self.along) else 0.0

    def left(self) -> float:
        """The path's length from the robot's projection to its end (feedback's distance_to_goal)."""
        return max(0.0, self.length - (0.0 if math.isnan(self.at) else self.at))

    def locate(self, position: Sequence[float]) -> float:
        """Where the robot at `position` is along the path (`at`, its length from the start to the robot's projection
        on it): the nearest point on the segments from TRACK_BACK behind where it was to TRACK_AHEAD ahead; the first
        time on the whole path, its earliest part within TRACK_SNAP of the nearest (a path ending where it began
        is driven, not ended at once). Vectorised over those segments."""
        n = len(self.xy)
        if n < 2:
            self.at = 0.0
            return self.at
        first = math.isnan(self.at)
        lo, hi = 0, n - 1   # segments lo .. hi - 1
        if not first:
            lo = max(0, int(np.searchsorted(self.along, self.at - TRACK_BACK, 'right')) - 1)
            hi = min(n - 1, max(lo + 1, int(np.searchsorted(self.along, self.at + TRACK_AHEAD, 'left'))))
        a, b = self.xy[lo:hi], self.xy[lo + 1:hi + 1]
        chord = b - a
        length2 = (chord * chord).sum(axis=1)
        p = np.asarray(position[:2], dtype=float) - a
        with np.errstate(invalid='ignore', divide='ignore'):
            t = np.where(length2 > 0.0, np.clip((p * chord).sum(axis=1) / length2, 0.0, 1.0), 0.0)
        off = np.hypot(*(p - t[:, None] * chord).T)
        k = int(np.flatnonzero(off <= off.min() + TRACK_SNAP)[0]) if first else int(np.argmin(off))
        self.at = float(self.along[lo + k] + t[k] * math.sqrt(length2[k]))
        return self.at

    def target(self, index: int, position: Sequence[float]) -> int:
        """The target to drive to now, from `index` on: the first not passed (more than `passing`, PASS_DISTANCE or
        twice goal_tolerance, ahead of the robot's projection, and as far from the robot), the last never passed."""
        last = len(self.targets) - 1
        while index < last:
            goal = self.targets[index].pose.position
            if self.target_along[index] - self.at > self.passing and \
                    math.hypot(goal.x - position[0], goal.y - position[1]) > self.passing:
                break
            index += 1
        return index


@dataclass
class Run:
    """One action goal under way: its poses, the one driven to, and how it ended."""

    handle: Any
    poses: GoalPoses | None            # None until checked (a goal refused before: none)
    kind: str                          # TO_POSE, THROUGH_POSES, WAYPOINTS or FOLLOW_PATH
    accepted: float                    # wall time
    began: float = math.nan            # node time (feedback's navigation_time, as Nav2's: its node clock)
    index: int = 0
    loops: int = 0                     # follow_waypoints: more passes over the list to make
    missed: list[Any] = field(default_factory=list)   # follow_waypoints: nav2_msgs MissedWaypoint
    path: GivenPath | None = None      # follow_path: the path (its targets driven to in turn: index)
    sent: PoseStamped | None = None    # the pose handed to the planner (identity: the planner took it or not)
    taken: bool = False                # the planner has made `sent` its goal
    sent_at: float = math.nan          # node time `sent` was handed to the planner
    held: float | None = None          # m/s: the speed held lately, as feedback saw the robot (the ETA's)
    last_position: tuple[float, float] | None = None
    last_at: float = -math.inf         # node time of last_position
    result: Any = None
    done: Any = None                   # an rclpy Future, set when the run ends: (terminal state, result)
    ended: list[str] = field(default_factory=list)


def companion_classes() -> list[Callable[[NavigateActions], Companion]]:
    """The planner's other Nav2 servers: paths (compute_path_to_pose, compute_path_through_poses), driving a given
    path and the behaviours (follow_path, spin, backup, drive_on_heading), the costmap-clearing services."""
    from fastep_ros.behaviour_actions import BehaviourActions
    from fastep_ros.costmap_services import CostmapServices
    from fastep_ros.path_actions import PathActions
    return [PathActions, BehaviourActions, CostmapServices]


class NavigateActions:
    """The planner's Nav2 action servers (see the module docstring). Its methods run on the planner's executor,
    but for the servers' callbacks (on_goal_request, on_cancel_request, the execute coroutines), which run on the
    action thread (`side`)."""

    def __init__(self, node: Any) -> None:
        """`node`: the planner node (fastep_ros.planner.PlannerNode), which owns this and imports it."""
        from nav2_msgs.action import FollowPath, FollowWaypoints, NavigateThroughPoses, NavigateToPose

        from fastep_ros.action_thread import ActionThread
        self.node = node
        self.run: Run | None = None
        self.feedback_at = -math.inf
        self.epoch = 0   # deactivations seen (executor: written; action thread: read at a goal's acceptance)
        self.served = {TO_POSE: NavigateToPose, THROUGH_POSES: NavigateThroughPoses, WAYPOINTS: FollowWaypoints,
                       FOLLOW_PATH: FollowPath}
        self._accepted_in: dict[int, int] = {}   # action thread only: id(goal request) -> epoch it was accepted in
        # id(follow_path request) -> its points, read on the action thread (set there, popped by the executor: one
        # dict operation each, atomic), so that a long path's Python objects are not read on the control tick.
        self._path_points: dict[int, NDArray[np.float64]] = {}
        self.side = ActionThread(node)
        try:
            # The other Nav2 servers a client calls, on the same node and thread (Companion).
            self.companions: list[Companion] = [make(self) for make in companion_classes()]
            self.handled_by: dict[str, Companion] = {name: c for c in self.companions for name in c.served}
            # An ended goal (its request, every pose) is released after ACTION_RESULT_TIMEOUT, not rclpy's 900 s.
            self.servers = [self.side.serve(action, name, self._execute(name), goal_callback=self.on_goal_request,
                                            cancel_callback=self.on_cancel_request,
                                            result_timeout=ACTION_RESULT_TIMEOUT)
                            for name, action in [*self.served.items(),
                                                 *((n, a) for c in self.companions for n, a in c.served.items())]]
            self.side.start()
        except BaseException:
            self.side.stop(ACTION_JOIN)
            raise

    @staticmethod
    def make(node: Any) -> NavigateActions | None:
        """The servers, or None (said once) where nav2_msgs cannot be imported."""
        try:
            return NavigateActions(node)
        except ImportError as exc:
            node.get_logger().info(f'nav2_msgs is not installed ({exc}): no navigate_to_pose action server '
                                   f'(goals on goal_pose only)')
            return None

    # ------------------------------------------------------------------------------------------ requests
    # On the action thread (rclpy calls them there, its request converted there).
    def on_goal_request(self, request: Any) -> Any:
        from rclpy.action import GoalResponse

        from fastep_ros.action_thread import release_poses
        epoch = self.epoch   # read before is_active: a deactivation after this read counts against the goal
        if not self.node.lifecycle.is_active:
            self.node.get_logger().warning('navigation goal rejected: the planner is not active (lifecycle)')
            release_poses(request)
            return GoalResponse.REJECT
        self._accepted_in[id(request)] = epoch   # the handle's request is this object (rclpy's ServerGoalHandle)
        path = getattr(request, 'path', None)    # a follow_path goal's nav_msgs/Path
        if path is not None and len(getattr(path, 'poses', ())) <= PATH_POSES_MAX:
            self._path_points[id(request)] = path_points(path.poses)
        return GoalResponse.ACCEPT

    def on_cancel_request(self, goal_handle: Any) -> Any:
        from rclpy.action import CancelResponse
        return CancelResponse.ACCEPT   # rclpy marks the goal CANCELING; the executor sees it on its next check

    def _execute(self, kind: str) -> Callable[[Any], Any]:
        async def execute(goal_handle: Any) -> Any:
            from rclpy.task import Future

            from fastep_ros.action_thread import release_poses
            from fastep_ros.planner_threads import ActionGoal
            done = Future()
            self.side.post(ActionGoal(kind, goal_handle, done, self._accepted_in.pop(id(goal_handle.request), -1)))
            await done   # set by the executor (finish), which then wakes this thread's executor
            how, result = done.result()
            _end(goal_handle, how, self.node.get_logger())
            release_poses(goal_handle.request)   # ended: its poses are not read again (a run keeps its own list)
            return result
        return execute

    # ------------------------------------------------------------------------------------------ runs
    def start(self, goal: Any, active: bool) -> None:
        """A goal handed over by the action thread (fastep_ros.planner_threads.ActionGoal): its run begins,
        preempting the one under way; a goal accepted before a deactivation since, or one taken while inactive,
        ends aborted."""
        request = goal.handle.request
        kind = goal.kind
        points = self._path_points.pop(id(request), None)   # follow_path: its points, read on the action thread
        if not active or goal.epoch != self.epoch:
            stale = Run(goal.handle, None, kind, time.monotonic(), done=goal.done)
            self.finish(stale, 'aborted', 'the planner was deactivated', UNKNOWN_DRIVING)
            return
        if kind == FOLLOW_PATH:
            self.start_path(goal, points)
            return
        poses = [request.pose] if kind == TO_POSE else request.poses
        preempted = self.run is not None
        if self.run is not None:
            self.finish(self.run, 'aborted', 'preempted by a new goal', PREEMPTED)
        run = self.run = Run(goal.handle, None, kind, time.monotonic(), self.node.now(), done=goal.done)
        if kind == WAYPOINTS:
            run.index, run.loops = int(request.goal_index), int(request.number_of_loops)
        if len(poses) > GOAL_POSES_MAX:
            self.finish(run, 'aborted', f'goal refused: {len(poses)} poses, more than the {GOAL_POSES_MAX} a '
                        'goal may have', UNKNOWN_PLANNING)
        elif not poses or run.index >= len(poses):
            self.finish(run, 'aborted', f'no poses to navigate through from index {run.index}',
                        WAYPOINTS_FAILED if kind == WAYPOINTS else UNKNOWN_PLANNING)
        else:
            run.poses = GoalPoses(self.node, poses)
            self.begin(run)
        if preempted and run.ended:   # refused at once: the goal it preempted is not driven on either
            self.node.drop_goal(f'{kind} goal refused: {run.result.error_msg}')

    def start_path(self, goal: Any, points: NDArray[np.float64] | None = None) -> None:
        """A follow_path goal: it preempts the run under way (a follow_path one: a path update, as Nav2's
        controller_server takes it, the robot driving on to the new path's pose without a stop between); its path
        checked (GivenPath) and its first target handed to the planner; a path refused ends it at once, and stops
        the robot if it was driving for the goal preempted (as Nav2's, which publishes a zero velocity)."""
        previous = self.run
        if previous is not None:
            update = previous.kind == FOLLOW_PATH
            self.finish(previous, 'aborted', 'replaced by a new path (a path update)' if update else
                        'preempted by a new goal', PREEMPTED)
        run = self.run = Run(goal.handle, None, FOLLOW_PATH, time.monotonic(), self.node.now(), done=goal.done)
        path = run.path = GivenPath(self.node, goal.handle.request.path, points)
        if path.code:
            self.finish(run, 'aborted', f'path refused: {path.problem}', path.code)
            if previous is not None:
                self.node.drop_goal(f'follow_path: path refused: {path.problem}')
            return
        if path.skipped:
            self.node.get_logger().warning(
                f'follow_path: {path.skipped} of the {len(path.targets) + path.skipped} poses the path is driven '
                'through are within the robot\'s radius of an obstacle or occupied: driven round')
        run.index = -1
        self.follow(run)

    def follow(self, run: Run) -> None:
        """follow_path, on every control tick: where the robot is along the path (GivenPath.locate), and the next
        target handed to the planner once the one driven to is passed (a little before it: no stop on the way)."""
        path = run.path
        assert path is not None
        node = self.node
        state, _ = node.inputs.state(node.now())
        index = max(run.index, 0)
        if state is not None:
            position = (float(state[0]), float(state[1]))
            path.locate(position)
            index = path.target(index, position)
        if index != run.index:
            run.index = index
            run.sent, run.taken, run.sent_at = path.targets[index], False, node.now()
            node.on_goal(run.sent)

    # ------------------------------------------------------------------------------------------ progress
    def begin(self, run: Run) -> None:
        """A goal whose poses were checked: refused whole (a pose refused, except follow_waypoints without
        stop_on_failure), or its first usable pose driven to; the robot has not moved for it yet."""
        poses = run.poses
        assert poses is not None
        refused = poses.refused()
        if run.kind == WAYPOINTS and run.loops == 0:
            refused = refused[refused >= run.index]   # the waypoints visited: from goal_index (no loops after)
        every = run.kind == WAYPOINTS and run.loops > 0 and len(refused) == len(poses)
        if len(refused):
            first = int(refused[0])
            problem = poses.problem(first)
            code = navigation_code(error_code(problem, refused=True))
            if run.kind == TO_POSE:
                self.finish(run, 'aborted', f'goal refused: {problem}', code)
                return
            if run.kind == THROUGH_POSES:
                self.finish(run, 'aborted', f'goal refused: pose {first}: {problem}', code)
                return
            if self.node.stop_on_failure:
                from nav2_msgs.msg import MissedWaypoint
                run.index = first
                run.missed.append(MissedWaypoint(index=first, goal=poses.given[first], error_code=code))
                self.finish(run, 'aborted', f'waypoint {first}: goal refused: {problem} (stop_on_failure)',
                            WAYPOINTS_FAILED)
                return
            if every:
                run.loops = 0   # every pass would miss the same waypoints: one pass, not number_of_loops more
            self.node.get_logger().warning(
                f'follow_waypoints: {len(refused)} of {len(poses)} waypoints refused, missed when reached (first: '
                f'waypoint {first}: {problem}){": one pass, no loops" if every else ""}')
        self.drive_on(run, step=False)

    def drive_on(self, run: Run, step: bool = True) -> None:
        """Drive to the run's next pose (step: after the one at run.index; else that one), the list again
        (follow_waypoints' loops), or succeed; a waypoint refused when the goal came is missed on the way. A loop,
        not a recursion: every waypoint of a goal may have been refused."""
        from nav2_msgs.msg import MissedWaypoint
        poses = run.poses
        assert poses is not None
        while True:
            if step:
                if run.index + 1 < len(poses):
                    run.index += 1
                elif run.loops > 0:
                    run.loops, run.index = run.loops - 1, 0
                else:
                    self.finish(run, 'succeeded', '', 0)
                    return
            step = True
            code = int(poses.codes[run.index])
            if not code:
                break
            run.missed.append(MissedWaypoint(index=run.index, goal=poses.given[run.index],
                                             error_code=navigation_code(code)))
        run.sent, run.taken, run.sent_at = poses.msg(run.index), False, self.node.now()
        self.node.on_goal(run.sent)

    def failed(self, run: Run, reason: str, code: int) -> None:
        """The pose driven to cannot be reached: the goal ends, or (follow_waypoints without stop_on_failure) the
        waypoint is missed and the next one is driven to. `code`: ComputePathToPose's (error_code); follow_path
        ends with FollowPath's (follow_path_code)."""
        if run.kind == FOLLOW_PATH:
            self.finish(run, 'aborted', reason, follow_path_code(reason))
            return
        code = navigation_code(code)
        if run.kind != WAYPOINTS:
            self.finish(run, 'aborted', reason, code)
            return
        from nav2_msgs.msg import MissedWaypoint
        assert run.poses is not None
        run.missed.append(MissedWaypoint(index=run.index, goal=run.poses.given[run.index], error_code=code))
        if self.node.stop_on_failure:
            self.finish(run, 'aborted', f'waypoint {run.index}: {reason} (stop_on_failure)', WAYPOINTS_FAILED)
        else:
            self.node.get_logger().warning(f'waypoint {run.index} missed: {reason}')
            self.drive_on(run)

    def check(self) -> None:
        """On every control tick (and the wall tick, and deactivate): the goals the action thread handed over, then
        feedback, and the end of the run when the planner says it ended."""
        active = self.node.lifecycle.is_active
        if not active:
            self.epoch += 1   # a goal accepted before now is not driven (it may be handed over after this check)
        for goal in self.side.take():
            companion = self.handled_by.get(goal.kind)
            if companion is not None:
                companion.start(goal, active)
            else:
                self.start(goal, active)
        for companion in self.companions:
            companion.check()
        run = self.run
        if run is None:
            return
        node, nav = self.node, self.node.navigator
        if run.handle.is_cancel_requested:
            node.drop_goal('goal canceled')
            self.finish(run, 'canceled', 'canceled', 0)
            return
        if not active:
            self.finish(run, 'aborted', 'the planner was deactivated', UNKNOWN_DRIVING)
            return
        if nav is None:
            return
        if run.path is not None:
            self.follow(run)
        if node.goal_msg is run.sent:
            run.taken = True
        elif run.taken:
            self.finish(run, 'aborted', 'preempted by a goal on goal_pose', PREEMPTED)   # Nav2: goal_pose is a goal
            return
        elif node.refused_msg is run.sent:
            # Refused by the planner itself (its world changed since goal_problem looked): said on goal_refused.
            reason = node.goal_refused.split(' refused: ', 1)[-1]
            self.failed(run, f'goal refused: {reason}', error_code(reason, refused=True))
            return
        else:
            # The planner has not taken it yet (the planning thread takes it between two passes): a pass that does
            # not end keeps it from ever doing so; after planning_timeout the goal ends (dropped when taken late).
            waited = node.now() - run.sent_at
            if 0.0 < node.planning_timeout <= waited:
                reason = f'planning timed out: the goal not taken in {waited:.1f} s (planning_timeout ' \
                         f'{node.planning_timeout:g} s)'
                node.drop_goal(reason)
                self.failed(run, reason, error_code(reason))
            return
        if node.plan_failed:   # no plan for planning_timeout (the planning side fails it when its pass ends)
            self.failed(run, node.plan_failed, error_code(node.plan_failed))
            return
        mode = nav.mode.value
        if mode == 'failed':
            self.failed(run, nav.reason, error_code(nav.reason))
            return
        if mode == 'arrived':
            if run.path is None:
                self.drive_on(run)
            elif run.index + 1 < len(run.path.targets):   # stopped short of passing it (a slow robot): the next
                run.index += 1
                run.sent, run.taken, run.sent_at = run.path.targets[run.index], False, node.now()
                node.on_goal(run.sent)
            else:
                self.finish(run, 'succeeded', '', 0)
            return
        now = time.monotonic()
        if now - self.feedback_at >= FEEDBACK_PERIOD:
            self.feedback_at = now
            self.publish_feedback(run, now)

    def publish_feedback(self, run: Run, now: float) -> None:
        from builtin_interfaces.msg import Duration

        from msg_tools import convert
        node, nav = self.node, self.node.navigator
        state, _ = node.inputs.state(node.now())
        if state is None or nav is None:
            return
        feedback = self.served[run.kind].Feedback()
        if run.path is not None:   # follow_path: as Nav2's controller_server fills it, but the speed measured
            feedback.distance_to_goal = run.path.left()
            feedback.speed = self.speed()
            run.handle.publish_feedback(feedback)
            return
        if run.kind == WAYPOINTS:
            feedback.current_waypoint = run.index
            run.handle.publish_feedback(feedback)
            return
        position = (float(state[0]), float(state[1]))
        yaw = 0.0 if node.model == 'point_mass' else float(state[2])   # a point mass has no heading
        feedback.current_pose = convert.point_to_pose_stamped(position, node.stamp(), node.frame_id, yaw)
        poses = run.poses
        assert poses is not None
        remaining, planned = self.distance_remaining(run, position)
        if not planned and node.now() - run.sent_at < WAY_WAIT:
            return   # no pass has planned the way to this pose yet (one comes within a tick or two)
        speed = node.params.max_speed   # the most it can hold (a speed limit caps it: on_speed_limit)
        if not speed > 0.0:   # unlimited: the speed driven now, at least 1 m/s
            speed = max(1.0, math.hypot(*node.last_command[:2]) if node.model == 'point_mass' else
                        abs(float(node.last_command[0])))
        now = node.now()
        if run.last_position is not None and now > run.last_at:
            # The speed it holds lately (turns in place, slowing round obstacles, a base slower than told), smoothed
            # over HELD_TIME; from `speed` at the start.
            step = now - run.last_at
            weight = 1.0 - math.exp(-step / HELD_TIME)
            run.held = speed if run.held is None else run.held
            run.held += weight * (math.dist(position, run.last_position) / step - run.held)
        run.last_position, run.last_at = position, now
        if run.held is not None:
            speed = min(speed, max(run.held, HELD_LEAST * speed))
        feedback.navigation_time = _duration(Duration, now - run.began)
        feedback.estimated_time_remaining = _duration(Duration, eta(remaining, speed, node.params.max_acceleration))
        feedback.number_of_recoveries = min(int(nav.escapes + nav.manoeuvres), 32767)
        feedback.distance_remaining = float(remaining)
        if run.kind == THROUGH_POSES:
            feedback.number_of_poses_remaining = min(len(poses) - run.index, 32767)
        run.handle.publish_feedback(feedback)

    def speed(self) -> float:
        """The robot's speed now: its odometry's twist, or the last command where that is not the base's velocity."""
        node = self.node
        velocity = node.inputs.velocity()
        command = node.last_command if velocity is None else velocity
        return float(math.hypot(*command[:2]) if node.model == 'point_mass' else abs(float(command[0])))

    def distance_remaining(self, run: Run, position: tuple[float, float]) -> tuple[float, bool]:
        """The length of the way left from `position`: along the route the newest pass follows to the pose driven to
        (fastep_ros.progress.Way; the straight run without a route, or before a pass planned for that pose), then
        the straight legs through the poses after it (GoalPoses.after, precomputed); and whether a pass has planned
        the way to that pose (False: the straight run was measured)."""
        node, poses = self.node, run.poses
        assert poses is not None
        target = (float(poses.xy[run.index, 0]), float(poses.xy[run.index, 1]))
        if node.planning is not None:
            result = node.planning.plan   # read once: the newest pass's result (its way frozen with its plan)
            way = None if result is None else result.way
        else:
            way = None if node.navigator is None else Way.of(node.navigator)   # lock step: the executor's own
        planned = way is not None and way.leads_to(target)
        if way is None or not planned:
            way = Way(target, np.zeros((0, 2)), np.zeros(0))
        return way.remaining(position) + float(poses.after[run.index]), planned

    def finish(self, run: Run, how: str, message: str, code: int) -> None:
        """End a run: its result (error code and message) and terminal state handed to its execute coroutine, which
        the action thread resumes (woken) to make the transition and send the result."""
        if run.ended:
            return
        run.ended.append(how)
        result = self.served[run.kind].Result()
        result.error_code, result.error_msg = code, message
        if run.kind == WAYPOINTS:
            result.missed_waypoints = run.missed
        run.result = result
        if how not in ('succeeded', 'canceled'):
            self.node.get_logger().info(f'navigation goal aborted: {message}')
        if self.run is run:
            self.run = None
        run.done.set_result((how, result))
        self.side.wake()

    def destroy(self) -> None:
        """Every goal under way or handed over ended (aborted), then the action thread stopped and joined: its
        servers, executor and node destroyed. Once (cleanup, shutdown, destroy_node)."""
        if self.run is not None:
            self.finish(self.run, 'aborted', 'the planner is shutting down', UNKNOWN_DRIVING)
        for companion in self.companions:
            companion.destroy()
        for goal in self.side.take():
            owner = self.handled_by.get(goal.kind)
            if owner is not None:
                owner.end(goal, 'aborted', 'the planner is shutting down')
                continue
            self.finish(Run(goal.handle, None, goal.kind, time.monotonic(), done=goal.done), 'aborted',
                        'the planner is shutting down', UNKNOWN_DRIVING)
        if not self.side.stop(ACTION_JOIN):
            self.node.get_logger().warning(f'{self.side.name}: a request under way did not end within '
                                           f'{ACTION_JOIN:g} s; its thread releases the action servers when done')


def _end(handle: Any, how: str, logger: Any) -> None:
    """The action thread: a goal's terminal transition, as the executor chose it (succeeded, canceled, else
    aborted). One the goal's state does not allow (rclpy raises) is logged; rclpy then aborts the goal."""
    try:
        if how == 'succeeded':
            handle.succeed()
        elif how == 'canceled':
            handle.canceled()
        else:
            handle.abort()
    except Exception as exc:  # noqa: BLE001  rclpy's RCLError for a transition the goal's state does not have
        logger.warning(f'navigation goal: {how} refused by its state ({exc})')


def _duration(cls: Any, seconds: float) -> Any:
    seconds = max(0.0, min(seconds, 2.0 ** 31 - 1))
    whole = math.floor(seconds)
    return cls(sec=int(whole), nanosec=min(int((seconds - whole) * 1e9), 999_999_999))
