"""Nav2's navigation actions, served by the planner: `navigate_to_pose`, `navigate_through_poses`, `follow_waypoints`.

nav2_msgs/action/NavigateToPose, NavigateThroughPoses and FollowWaypoints with Nav2 Jazzy's definitions, in the
planner's namespace, so that a client written for Nav2 (nav2_simple_commander's BasicNavigator, RViz's Nav2
panel) commands a fastep robot unchanged. As in Nav2: goals are accepted only while the node is active; a new
goal preempts the one under way (ABORTED, "preempted by a new goal"); feedback comes every FEEDBACK_PERIOD wall
seconds, its distance_remaining along the route the robot follows (fastep_ros.progress.Way, frozen by each pass);
the result is SUCCEEDED, ABORTED with one of Nav2's error codes (ERROR_CODES) and the planner's reason (207 when
planning left no plan for planning_timeout: every goal ends), or CANCELED (the robot brakes to a stop).
follow_waypoints follows Nav2's waypoint follower (goal_index, number_of_loops, missed waypoints,
`stop_on_failure`). Behaviour in full: docs/robots_and_goals.md.

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

from fastep_ros.limits import ACTION_RESULT_TIMEOUT, GOAL_POSES_MAX
from fastep_ros.progress import Way, eta

__all__ = ['ERROR_CODES', 'FEEDBACK_PERIOD', 'GoalPoses', 'NavigateActions', 'error_code']

FEEDBACK_PERIOD = 0.1   # wall seconds between feedback messages (Nav2's navigator sends one per tree tick)
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
TASK_EXECUTOR_FAILED = 601   # FollowWaypoints: a waypoint failed (stop_on_failure)
GOAL_OCCUPIED, GOAL_OUTSIDE_MAP, TF_ERROR = 206, 204, 202   # ComputePathToPose, as ERROR_CODES gives them
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


@dataclass
class Run:
    """One action goal under way: its poses, the one driven to, and how it ended."""

    handle: Any
    poses: GoalPoses | None            # None until checked (a goal refused before: none)
    kind: str                          # TO_POSE, THROUGH_POSES or WAYPOINTS
    accepted: float                    # wall time
    began: float = math.nan            # node time (feedback's navigation_time, as Nav2's: its node clock)
    index: int = 0
    loops: int = 0                     # follow_waypoints: more passes over the list to make
    missed: list[Any] = field(default_factory=list)   # follow_waypoints: nav2_msgs MissedWaypoint
    sent: PoseStamped | None = None    # the pose handed to the planner (identity: the planner took it or not)
    taken: bool = False                # the planner has made `sent` its goal
    sent_at: float = math.nan          # node time `sent` was handed to the planner
    result: Any = None
    done: Any = None                   # an rclpy Future, set when the run ends: (terminal state, result)
    ended: list[str] = field(default_factory=list)


class NavigateActions:
    """The planner's Nav2 action servers (see the module docstring). Its methods run on the planner's executor,
    but for the servers' callbacks (on_goal_request, on_cancel_request, the execute coroutines), which run on the
    action thread (`side`)."""

    def __init__(self, node: Any) -> None:
        """`node`: the planner node (fastep_ros.planner.PlannerNode), which owns this and imports it."""
        from nav2_msgs.action import FollowWaypoints, NavigateThroughPoses, NavigateToPose

        from fastep_ros.action_thread import ActionThread
        self.node = node
        self.run: Run | None = None
        self.feedback_at = -math.inf
        self.epoch = 0   # deactivations seen (executor: written; action thread: read at a goal's acceptance)
        self.served = {TO_POSE: NavigateToPose, THROUGH_POSES: NavigateThroughPoses, WAYPOINTS: FollowWaypoints}
        self._accepted_in: dict[int, int] = {}   # action thread only: id(goal request) -> epoch it was accepted in
        self.side = ActionThread(node)
        try:
            # An ended goal (its request, every pose) is released after ACTION_RESULT_TIMEOUT, not rclpy's 900 s.
            self.servers = [self.side.serve(action, name, self._execute(name), goal_callback=self.on_goal_request,
                                            cancel_callback=self.on_cancel_request,
                                            result_timeout=ACTION_RESULT_TIMEOUT)
                            for name, action in self.served.items()]
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
        if not active or goal.epoch != self.epoch:
            stale = Run(goal.handle, None, kind, time.monotonic(), done=goal.done)
            self.finish(stale, 'aborted', 'the planner was deactivated', UNKNOWN_DRIVING)
            return
        poses = [request.pose] if kind == TO_POSE else request.poses
        if self.run is not None:
            self.finish(self.run, 'aborted', 'preempted by a new goal', UNKNOWN_DRIVING)
        run = self.run = Run(goal.handle, None, kind, time.monotonic(), self.node.now(), done=goal.done)
        if kind == WAYPOINTS:
            run.index, run.loops = int(request.goal_index), int(request.number_of_loops)
        if len(poses) > GOAL_POSES_MAX:
            self.finish(run, 'aborted', f'goal refused: {len(poses)} poses, more than the {GOAL_POSES_MAX} a '
                        'goal may have', UNKNOWN_PLANNING)
        elif not poses or run.index >= len(poses):
            self.finish(run, 'aborted', f'no poses to navigate through from index {run.index}', UNKNOWN_PLANNING)
        else:
            run.poses = GoalPoses(self.node, poses)
            self.begin(run)

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
            code = error_code(problem, refused=True)
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
                self.finish(run, 'aborted', f'waypoint {first}: goal refused: {problem}', TASK_EXECUTOR_FAILED)
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
            run.missed.append(MissedWaypoint(index=run.index, goal=poses.given[run.index], error_code=code))
        run.sent, run.taken, run.sent_at = poses.msg(run.index), False, self.node.now()
        self.node.on_goal(run.sent)

    def failed(self, run: Run, reason: str, code: int) -> None:
        """The pose driven to cannot be reached: the goal ends, or (follow_waypoints without stop_on_failure) the
        waypoint is missed and the next one is driven to."""
        if run.kind != WAYPOINTS:
            self.finish(run, 'aborted', reason, code)
            return
        from nav2_msgs.msg import MissedWaypoint
        assert run.poses is not None
        run.missed.append(MissedWaypoint(index=run.index, goal=run.poses.given[run.index], error_code=code))
        if self.node.stop_on_failure:
            self.finish(run, 'aborted', f'waypoint {run.index}: {reason}', TASK_EXECUTOR_FAILED)
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
            self.start(goal, active)
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
        if node.goal_msg is run.sent:
            run.taken = True
        elif run.taken:
            self.finish(run, 'aborted', 'preempted by a goal on goal_pose', UNKNOWN_DRIVING)
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
            self.drive_on(run)
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
        if run.kind == WAYPOINTS:
            feedback.current_waypoint = run.index
            run.handle.publish_feedback(feedback)
            return
        position = (float(state[0]), float(state[1]))
        feedback.current_pose = convert.point_to_pose_stamped(position, node.stamp(), node.frame_id)
        poses = run.poses
        assert poses is not None
        remaining, planned = self.distance_remaining(run, position)
        if not planned and node.now() - run.sent_at < WAY_WAIT:
            return   # no pass has planned the way to this pose yet (one comes within a tick or two)
        speed = node.params.max_speed   # the speed it can hold (a speed limit caps it: on_speed_limit)
        if not speed > 0.0:   # unlimited: the speed driven now, at least 1 m/s
            speed = max(1.0, math.hypot(*node.last_command[:2]) if node.model == 'point_mass' else
                        abs(float(node.last_command[0])))
        feedback.navigation_time = _duration(Duration, node.now() - run.began)
        feedback.estimated_time_remaining = _duration(Duration, eta(remaining, speed, node.params.max_acceleration))
        feedback.number_of_recoveries = min(int(nav.escapes + nav.manoeuvres), 32767)
        feedback.distance_remaining = float(remaining)
        if run.kind == THROUGH_POSES:
            feedback.number_of_poses_remaining = min(len(poses) - run.index, 32767)
        run.handle.publish_feedback(feedback)

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
        for goal in self.side.take():
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
