"""Nav2's navigation actions, served by the planner: `navigate_to_pose`, `navigate_through_poses`, `follow_waypoints`.

nav2_msgs/action/NavigateToPose, NavigateThroughPoses and FollowWaypoints with Nav2 Jazzy's definitions, in the
planner's namespace, so that a client written for Nav2 (nav2_simple_commander's BasicNavigator, RViz's Nav2
panel) commands a fastep robot unchanged. As in Nav2: goals are accepted only while the node is active; a new
goal preempts the one under way (ABORTED, "preempted by a new goal"); feedback comes every FEEDBACK_PERIOD wall
seconds; the result is SUCCEEDED, ABORTED with one of Nav2's error codes (ERROR_CODES) and the planner's reason,
or CANCELED (the robot brakes to a stop). follow_waypoints follows Nav2's waypoint follower (goal_index,
number_of_loops, missed waypoints, `stop_on_failure`). Behaviour in full: docs/robots_and_goals.md.

A goal on the `goal_pose` topic goes the same way (the planner's take_goal) and preempts an action goal under
way. Without nav2_msgs the planner runs without these servers and says so once.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

from geometry_msgs.msg import PoseStamped

__all__ = ['ERROR_CODES', 'FEEDBACK_PERIOD', 'NavigateActions', 'error_code']

FEEDBACK_PERIOD = 0.1   # wall seconds between feedback messages (Nav2's navigator sends one per tree tick)

# Nav2 Jazzy's error codes (nav2_msgs ComputePathToPose and FollowPath), by what the planner's reason says.
ERROR_CODES: tuple[tuple[str, int], ...] = (
    ('no valid path', 208),            # ComputePathToPose.NO_VALID_PATH
    ('occupied', 206),                 # GOAL_OCCUPIED
    ('inside an obstacle', 206),
    ('outside the map', 204),          # GOAL_OUTSIDE_MAP
    ('frame', 202),                    # TF_ERROR
    ('failed to make progress', 105),  # FollowPath.FAILED_TO_MAKE_PROGRESS
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


@dataclass
class Run:
    """One action goal under way: its poses, the one driven to, and how it ended."""

    handle: Any
    poses: list[PoseStamped]
    kind: str                          # TO_POSE, THROUGH_POSES or WAYPOINTS
    accepted: float                    # wall time
    index: int = 0
    loops: int = 0                     # follow_waypoints: more passes over the list to make
    missed: list[Any] = field(default_factory=list)   # follow_waypoints: nav2_msgs MissedWaypoint
    sent: PoseStamped | None = None    # the pose handed to the planner (identity: the planner took it or not)
    taken: bool = False                # the planner has made `sent` its goal
    result: Any = None
    done: Any = None                   # an rclpy Future, set when the run ends
    ended: list[str] = field(default_factory=list)


class NavigateActions:
    """The planner's Nav2 action servers (see the module docstring)."""

    def __init__(self, node: Any) -> None:
        """`node`: the planner node (fastep_ros.planner.PlannerNode), which owns this and imports it."""
        from nav2_msgs.action import FollowWaypoints, NavigateThroughPoses, NavigateToPose
        from rclpy.action import ActionServer
        self.node = node
        self.run: Run | None = None
        self.feedback_at = -math.inf
        self.served = {TO_POSE: NavigateToPose, THROUGH_POSES: NavigateThroughPoses, WAYPOINTS: FollowWaypoints}
        self.servers = [ActionServer(node, action, name, self._execute(name), goal_callback=self.on_goal_request,
                                     cancel_callback=self.on_cancel_request)
                        for name, action in self.served.items()]

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
    def on_goal_request(self, request: Any) -> Any:
        from rclpy.action import GoalResponse
        if not self.node.lifecycle.is_active:
            self.node.get_logger().warning('navigation goal rejected: the planner is not active (lifecycle)')
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def on_cancel_request(self, goal_handle: Any) -> Any:
        from rclpy.action import CancelResponse
        return CancelResponse.ACCEPT

    def _execute(self, kind: str) -> Callable[[Any], Any]:
        async def execute(goal_handle: Any) -> Any:
            from rclpy.task import Future
            request = goal_handle.request
            poses = [request.pose] if kind == TO_POSE else list(request.poses)
            if self.run is not None:
                self.finish(self.run, 'aborted', 'preempted by a new goal', UNKNOWN_DRIVING)
            run = self.run = Run(goal_handle, poses, kind, time.monotonic(), done=Future())
            if kind == WAYPOINTS:
                run.index, run.loops = int(request.goal_index), int(request.number_of_loops)
            if not poses or run.index >= len(poses):
                self.finish(run, 'aborted', f'no poses to navigate through from index {run.index}', UNKNOWN_PLANNING)
            else:
                self.send(run)
            await run.done
            return run.result
        return execute

    # ------------------------------------------------------------------------------------------ progress
    def send(self, run: Run) -> None:
        """Hand the run's next pose to the planner (as a goal on goal_pose would be), or end it if refused."""
        pose, problem = self.node.goal_in_map(run.poses[run.index])   # a pose in another frame: through TF
        if problem:
            self.failed(run, f'goal refused: {problem}', error_code(problem, refused=True))
            return
        problem = self.node.goal_problem(pose)
        if problem:
            self.failed(run, f'goal refused: {problem}', error_code(problem, refused=True))
            return
        run.sent, run.taken = pose, False
        self.node.goal_refused = ''   # a refusal from before is not this goal's (check reads it)
        self.node.on_goal(pose)

    def failed(self, run: Run, reason: str, code: int) -> None:
        """The pose driven to cannot be reached: the goal ends, or (follow_waypoints without stop_on_failure) the
        waypoint is missed and the next one is driven to."""
        if run.kind != WAYPOINTS:
            self.finish(run, 'aborted', reason, code)
            return
        from nav2_msgs.msg import MissedWaypoint
        run.missed.append(MissedWaypoint(index=run.index, goal=run.poses[run.index], error_code=code))
        if self.node.stop_on_failure:
            self.finish(run, 'aborted', f'waypoint {run.index}: {reason}', TASK_EXECUTOR_FAILED)
        else:
            self.node.get_logger().warning(f'waypoint {run.index} missed: {reason}')
            self.next_pose(run)

    def next_pose(self, run: Run) -> None:
        """After a pose reached (or missed): the next one, the list again (follow_waypoints' loops), or success."""
        if run.index + 1 < len(run.poses):
            run.index += 1
        elif run.loops > 0:
            run.loops, run.index = run.loops - 1, 0
        else:
            self.finish(run, 'succeeded', '', 0)
            return
        self.send(run)

    def check(self) -> None:
        """On every control tick: feedback, and the end of the run when the planner says it ended."""
        run = self.run
        if run is None:
            return
        node, nav = self.node, self.node.navigator
        if run.handle.is_cancel_requested:
            node.drop_goal('goal canceled')
            self.finish(run, 'canceled', 'canceled', 0)
            return
        if not node.lifecycle.is_active:
            self.finish(run, 'aborted', 'the planner was deactivated', UNKNOWN_DRIVING)
            return
        if nav is None:
            return
        if node.goal_msg is run.sent:
            run.taken = True
        elif run.taken:
            self.finish(run, 'aborted', 'preempted by a goal on goal_pose', UNKNOWN_DRIVING)
            return
        elif node.goal_refused.startswith(_refusal_of(run.sent)):
            # Refused by the planner itself (its world changed since goal_problem looked): said on goal_refused.
            reason = node.goal_refused.split(' refused: ', 1)[-1]
            self.failed(run, f'goal refused: {reason}', error_code(reason, refused=True))
            return
        else:
            return   # the planner has not taken it yet (the planning thread takes it between two passes)
        mode = nav.mode.value
        if mode == 'failed':
            self.failed(run, nav.reason, error_code(nav.reason))
            return
        if mode == 'arrived':
            self.next_pose(run)
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
        remaining, at = 0.0, position
        ahead = [] if nav.target is None else [(float(nav.target[0]), float(nav.target[1]))]
        for pose in run.poses[run.index:]:
            ahead.append((pose.pose.position.x, pose.pose.position.y))
        for point in ahead:
            remaining += math.hypot(point[0] - at[0], point[1] - at[1])
            at = point
        speed = max(math.hypot(*node.last_command[:2]) if node.model == 'point_mass' else abs(node.last_command[0]),
                    node.params.max_speed if node.params.max_speed > 0 else 1.0)
        feedback.navigation_time = _duration(Duration, now - run.accepted)
        feedback.estimated_time_remaining = _duration(Duration, remaining / speed)
        feedback.number_of_recoveries = min(int(nav.escapes + nav.manoeuvres), 32767)
        feedback.distance_remaining = float(remaining)
        if run.kind == THROUGH_POSES:
            feedback.number_of_poses_remaining = len(run.poses) - run.index
        run.handle.publish_feedback(feedback)

    def finish(self, run: Run, how: str, message: str, code: int) -> None:
        """End a run: its result (error code and message), its goal's state, its execute coroutine resumed."""
        if run.ended:
            return
        run.ended.append(how)
        result = self.served[run.kind].Result()
        result.error_code, result.error_msg = code, message
        if run.kind == WAYPOINTS:
            result.missed_waypoints = run.missed
        run.result = result
        if how == 'succeeded':
            run.handle.succeed()
        elif how == 'canceled':
            run.handle.canceled()
        else:
            run.handle.abort()
            self.node.get_logger().info(f'navigation goal aborted: {message}')
        if self.run is run:
            self.run = None
        run.done.set_result(True)

    def destroy(self) -> None:
        if self.run is not None:
            self.finish(self.run, 'aborted', 'the planner is shutting down', UNKNOWN_DRIVING)
        for server in self.servers:
            server.destroy()


def _refusal_of(pose: PoseStamped | None) -> str:
    """How the planner's goal_refused begins for this goal (take_goal's wording), or a text nothing begins with."""
    if pose is None:
        return '\0'
    return f'goal ({pose.pose.position.x:g}, {pose.pose.position.y:g}) refused'


def _duration(cls: Any, seconds: float) -> Any:
    seconds = max(0.0, min(seconds, 2.0 ** 31 - 1))
    whole = math.floor(seconds)
    return cls(sec=int(whole), nanosec=min(int((seconds - whole) * 1e9), 999_999_999))
