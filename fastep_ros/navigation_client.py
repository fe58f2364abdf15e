"""A small client of the planner's Nav2 actions, with the verbs of nav2_simple_commander's BasicNavigator.

    from fastep_ros.navigation_client import NavigationClient

    nav = NavigationClient(namespace='/r1')            # its own node and context; rclpy.init is not needed
    nav.go_to_pose(2.0, 10.0)                          # or go_through_poses([...]), follow_waypoints([...])
    while not nav.is_task_complete():
        feedback = nav.get_feedback()                  # NavigateToPose.Feedback, or None before the first
    print(nav.get_result(), nav.result_message())      # 'succeeded' | 'aborted' | 'canceled' | 'rejected'
    nav.close()

It talks only actions (fastep_ros.navigate_actions on the planner, or Nav2's own servers: the same interface), so
a script written with it runs against Nav2 too. Poses are (x, y) or (x, y, yaw) in `frame` (default map), or
geometry_msgs/PoseStamped; (x, y) asks no heading (a quaternion of zero length, which fastep's planner takes for
none). is_task_complete spins the client's node for up to `spin` seconds.
"""

from __future__ import annotations

import math
from typing import Any, Sequence, TypeAlias

from geometry_msgs.msg import PoseStamped

__all__ = ['NavigationClient']

GoalPose: TypeAlias = 'Sequence[float] | PoseStamped'   # (x, y[, yaw]) in `frame`, or a PoseStamped
STATUS = {4: 'succeeded', 5: 'canceled', 6: 'aborted'}   # action_msgs/GoalStatus


class NavigationClient:
    """go_to_pose, go_through_poses, follow_waypoints, is_task_complete, get_feedback, cancel_task, get_result."""

    def __init__(self, namespace: str = '/', frame: str = 'map', domain_id: int | None = None,
                 server_timeout: float = 30.0) -> None:
        import rclpy
        from nav2_msgs.action import FollowWaypoints, NavigateThroughPoses, NavigateToPose
        from rclpy.action import ActionClient
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions
        self.context = rclpy.Context()
        rclpy.init(args=[], context=self.context, domain_id=domain_id,
                   signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node('navigation_client', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.frame = frame
        base = namespace.rstrip('/')
        self.actions = {'to_pose': (NavigateToPose, f'{base}/navigate_to_pose'),
                        'through_poses': (NavigateThroughPoses, f'{base}/navigate_through_poses'),
                        'waypoints': (FollowWaypoints, f'{base}/follow_waypoints')}
        self.clients = {kind: ActionClient(self.node, action, name) for kind, (action, name) in self.actions.items()}
        self.server_timeout = server_timeout
        self.handle: Any = None
        self.result_future: Any = None
        self.feedback: Any = None
        self.status = ''
        self.result: Any = None

    # ------------------------------------------------------------------------------------------ tasks
    def go_to_pose(self, *pose: Any) -> bool:
        """Navigate to a pose ((x, y[, yaw]) or a PoseStamped); False if the planner rejected it."""
        goal = self.actions['to_pose'][0].Goal(pose=self.pose(pose[0] if len(pose) == 1 else pose))
        return self._send('to_pose', goal)

    def go_through_poses(self, poses: Sequence[GoalPose]) -> bool:
        goal = self.actions['through_poses'][0].Goal(poses=[self.pose(p) for p in poses])
        return self._send('through_poses', goal)

    def follow_waypoints(self, poses: Sequence[GoalPose], loops: int = 0, start: int = 0) -> bool:
        goal = self.actions['waypoints'][0].Goal(poses=[self.pose(p) for p in poses], number_of_loops=loops,
                                                 goal_index=start)
        return self._send('waypoints', goal)

    def is_task_complete(self, spin: float = 0.1) -> bool:
        """Whether the task has ended (spinning the client up to `spin` seconds for news)."""
        if self.result_future is None:
            return True
        self.executor.spin_until_future_complete(self.result_future, timeout_sec=spin)
        if not self.result_future.done():
            return False
        response = self.result_future.result()
        self.status, self.result = STATUS.get(response.status, f'status {response.status}'), response.result
        self.result_future = None
        return True

    def get_feedback(self) -> Any:
        """The newest feedback of the task under way (None before the first)."""
        return self.feedback

    def cancel_task(self, timeout: float = 10.0) -> bool:
        """Ask the planner to cancel the task (the robot brakes to a stop); True if it agreed."""
        if self.handle is None or self.result_future is None:
            return False
        future = self.handle.cancel_goal_async()
        self.executor.spin_until_future_complete(future, timeout_sec=timeout)
        return future.done() and len(future.result().goals_canceling) > 0

    def get_result(self) -> str:
        """How the last task ended: 'succeeded', 'aborted', 'canceled', 'rejected', or '' while under way."""
        return self.status

    def result_message(self) -> str:
        """The last result's error code and message ('' when it succeeded)."""
        if self.result is None or not getattr(self.result, 'error_code', 0):
            return ''
        return f'error {self.result.error_code}: {self.result.error_msg}'

    def close(self) -> None:
        import rclpy
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)

    # ------------------------------------------------------------------------------------------ helpers
    def pose(self, pose: GoalPose) -> PoseStamped:
        if isinstance(pose, PoseStamped):
            return pose
        out = PoseStamped()
        out.header.frame_id = self.frame
        out.pose.position.x, out.pose.position.y = float(pose[0]), float(pose[1])
        if len(pose) > 2:
            out.pose.orientation.z, out.pose.orientation.w = math.sin(0.5 * pose[2]), math.cos(0.5 * pose[2])
        else:
            out.pose.orientation.w = 0.0   # a quaternion of zero length: no heading to end in (fastep's planner)
        return out

    def _send(self, kind: str, goal: Any) -> bool:
        client = self.clients[kind]
        if not client.wait_for_server(timeout_sec=self.server_timeout):
            raise TimeoutError(f'no {self.actions[kind][1]} action server within {self.server_timeout:g} s')
        self.feedback, self.status, self.result = None, '', None
        future = client.send_goal_async(goal, feedback_callback=self._on_feedback)
        self.executor.spin_until_future_complete(future, timeout_sec=self.server_timeout)
        self.handle = future.result() if future.done() else None
        if self.handle is None or not self.handle.accepted:
            self.status, self.result_future = 'rejected', None
            return False
        self.result_future = self.handle.get_result_async()
        return True

    def _on_feedback(self, message: Any) -> None:
        self.feedback = message.feedback
